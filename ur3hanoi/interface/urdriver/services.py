"""The services UR's ROS 2 example clients call besides the trajectory controller, without a middleware: the
``controller_manager``'s ``list_controllers`` and ``switch_controller`` and the dashboard client's ``play``,
``stop`` and ``program_running``.

A binding's service callback (any thread) makes a :class:`ServiceCall`, hands it to the station
(:meth:`~ur3hanoi.interface.urdriver.station.DriverStation.on_service`) and waits (:meth:`ServiceCall.wait`); the
control thread answers it in its next cycle (:meth:`ServiceCall.answer`), so a switch or a program start happens
between two control cycles, as the controller manager switches between two updates.

The dashboard's answers are the robot's dashboard server's (``ur_robot_driver/src/dashboard_client_ros.cpp`` @ a16a268
passes them through as ``message``/``answer``): ``play`` "Starting program", ``stop`` "Stopped" (a stopped program:
"Failed to execute: Stop", ``success`` false), ``program_running`` "Program running: true" / "false". ``play``
starts the External Control program (the station's program state), ``stop`` stops it: the controllers follow as the
driver's ``controller_stopper`` makes them (:mod:`~ur3hanoi.interface.urdriver.controllers`).
"""

from __future__ import annotations

import threading
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from ur3hanoi.interface.urdriver.controllers import Controller, Ros1ControllerManager

if TYPE_CHECKING:
    from ur3hanoi.interface.urdriver.station import DriverStation

WAIT_S = 2.0
"""How long a service callback waits for the control loop [s] (it answers within a cycle while it runs)."""


class ServiceCall:
    """One call: ``kind`` (``list``, ``switch``, ``load`` (ROS 1, the name in ``activate``), ``play``, ``stop``,
    ``running``) and its arguments; the answer once :meth:`answer` ran."""

    def __init__(self, kind: str, activate: Sequence[str] = (), deactivate: Sequence[str] = (),
                 strictness: int = 0) -> None:
        self.kind, self.activate, self.deactivate, self.strictness = kind, tuple(activate), tuple(deactivate), \
            strictness
        self.result: Any = None
        self._done = threading.Event()

    def answer(self, station: DriverStation) -> None:
        """Answer in the control thread (the station's :meth:`_handle`)."""
        try:
            self.result = self._answer(station)
        finally:
            self._done.set()

    def _answer(self, station: DriverStation) -> Any:
        cm, running = station.controllers, station.program_running
        if self.kind == "list":
            return cm.listing()
        if self.kind == "load":
            return isinstance(cm, Ros1ControllerManager) and cm.load(self.activate[0])
        if self.kind == "switch":
            if isinstance(cm, Ros1ControllerManager):
                ok, message = cm.switch(self.activate, self.deactivate, self.strictness, running), cm.last_error
            else:
                ok, message = cm.switch(self.activate, self.deactivate, self.strictness)
            station.sync_controllers()
            return ok, message
        if self.kind == "play":
            station.set_program(True)
            return True, "Starting program"
        if self.kind == "stop":
            if not running:
                return False, "Failed to execute: Stop"
            station.set_program(False)
            return True, "Stopped"
        if self.kind == "running":
            return True, f"Program running: {'true' if running else 'false'}", running
        raise ValueError(f"unknown service call {self.kind!r}")

    def wait(self, timeout_s: float = WAIT_S) -> Any:
        """The answer, or None when the control loop did not answer within ``timeout_s`` (it stopped)."""
        return self.result if self._done.wait(timeout_s) else None


def controller_rows(listing: list[tuple[Controller, str]]) -> list[dict[str, Any]]:
    """``list_controllers``' rows as ``ControllerState`` fields (name, state, type, claimed interfaces, update
    rate)."""
    return [{"name": c.name, "state": state, "type": c.type, "update_rate": 500,
             "claimed_interfaces": list(c.interfaces) if state == "active" else [],
             "required_command_interfaces": list(c.interfaces)} for c, state in listing]
