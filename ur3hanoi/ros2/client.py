"""The arm as seen through the ROS 2 course topics: ``ur3e/command`` out, ``ur3e/position`` and
``ur3e/gripper_input`` in (``ros2-station`` or the course's real-robot bridge).

:class:`Ros2Arm` has the methods of :class:`ur3hanoi.ros.solve.Arm`, so :func:`ur3hanoi.ros.solve.run_lab_solve`
drives it with the same suction checks and halt as ``ros-solve``. It works in the controller convention like the
rest of ur3hanoi and converts at the topic (the bridge's course convention by default, :mod:`ur3hanoi.convention`).
A move is done when every joint is within ``tolerance_rad`` (0.0008 rad, what ENME480 student programs wait for);
``is_ready`` is not used (the bridge always sends true). ``held`` is ``dig_in`` bit 0.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.convention import from_controller, to_controller
from ur3hanoi.ros.errors import RosError


@dataclass(frozen=True)
class Ros2ArmConfig:
    """How the client commands and waits (see :class:`ur3hanoi.ros.client.ArmConfig`); ``tolerance_rad`` is the
    ENME480 programs' 0.0008 rad, ``convention`` the topics' joint convention."""

    v: float = 1.0
    a: float = 1.0
    tolerance_rad: float = 8e-4
    republish_s: float = 5.0
    poll_s: float = 0.004
    move_timeout_s: float = 60.0
    connect_timeout_s: float = 15.0
    convention: str = "course"


class Ros2Arm:
    """The robot through the ROS 2 course topics. Call :meth:`connect` first, :meth:`close` at the end.

    Args:
        config: command speed, tolerances, timeouts, convention.
        domain_id, network: the DDS domain and network (:class:`ur3hanoi.ros2.dds.Ros2Node`).
        log: where re-publish notices go.
    """

    def __init__(self, config: Ros2ArmConfig | None = None, domain_id: int = 0, network: str = "loopback",
                 log: Callable[[str], None] | None = None) -> None:
        self.config = config if config is not None else Ros2ArmConfig()
        self.domain_id = domain_id
        self.network = network
        self.log = log if log is not None else (lambda s: print(s, file=sys.stderr))
        self._q: FloatArray | None = None  # controller convention
        self._digin: int | None = None
        self._ain0 = float("nan")
        self._destination: FloatArray | None = None
        self._io = False
        self._node: Any = None
        self._pub: Any = None
        self._readers: tuple[Any, Any] | None = None
        self.commands_sent = 0

    def connect(self) -> None:
        """Join the domain and wait for the bridge's position and feedback and a ``ur3e/command`` subscriber.

        Raises:
            RosError: they do not appear within ``connect_timeout_s``.
        """
        from ur3hanoi.ros2.dds import Ros2Node
        from ur3hanoi.ros2.msgs import CommandUR3e, GripperInput, PositionUR3e

        self._node = node = Ros2Node("ur3hanoi_solve", self.domain_id, self.network)
        self._pub = node.publisher("ur3e/command", CommandUR3e)
        self._readers = (node.subscription("ur3e/position", PositionUR3e),
                         node.subscription("ur3e/gripper_input", GripperInput))
        node.announce()
        ok = self.wait_until(lambda: self._q is not None and self._digin is not None
                             and len(self._pub.get_matched_subscriptions()) > 0, self.config.connect_timeout_s)
        if not ok:
            missing = [name for name, seen in (("ur3e/position", self._q is not None),
                                               ("ur3e/gripper_input", self._digin is not None),
                                               ("a ur3e/command subscriber",
                                                len(self._pub.get_matched_subscriptions()) > 0)) if not seen]
            raise RosError(f"no {', '.join(missing)} within {self.config.connect_timeout_s:g} s on ROS_DOMAIN_ID "
                           f"{self.domain_id} ({self.network}): is ros2-station or the course's bridge running?")
        self._destination = self.q

    def close(self) -> None:
        if self._node is not None:
            self._node.close()
            self._node = None

    def _poll(self) -> None:
        """Take what arrived; keep the newest position and feedback."""
        if self._readers is None:
            return
        pos, grip = self._readers
        for msg in pos.take(N=100):
            if hasattr(msg, "position") and len(msg.position) == 6:
                self._q = to_controller(np.array(msg.position, dtype=float), self.config.convention)
        for msg in grip.take(N=100):
            if hasattr(msg, "dig_in"):
                self._digin, self._ain0 = int(msg.dig_in), float(msg.a_in0)

    @property
    def q(self) -> FloatArray:
        """The last ``ur3e/position`` [rad, controller convention]."""
        self._poll()
        if self._q is None:
            raise RosError("no ur3e/position received yet: call connect() first")
        return self._q.copy()

    def held(self) -> bool:
        self._poll()
        return bool((self._digin or 0) & 1)

    def feedback_text(self) -> str:
        return f"dig_in={self._digin}, a_in0={self._ain0:.2f} V"

    def _publish(self, destination: FloatArray, io_0: bool) -> Any:
        from ur3hanoi.ros2.msgs import CommandUR3e

        dest = from_controller(np.asarray(destination, dtype=float), self.config.convention)
        msg = CommandUR3e(destination=[float(x) for x in dest], v=self.config.v, a=self.config.a, io_0=io_0)
        self._pub.write(msg)
        self.commands_sent += 1
        return msg

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while True:
            self._poll()
            if predicate():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(self.config.poll_s)

    def move(self, q: FloatArray, watch: Callable[[], None] | None = None) -> None:
        """Command ``q`` [rad, controller convention] with the current suction state; wait until within tolerance.

        Raises:
            RosError: not reached within ``move_timeout_s`` (re-published every ``republish_s``).
        """
        cfg = self.config
        goal = np.array(q, dtype=float)
        msg = self._publish(goal, self._io)
        self._destination = goal
        t0 = last = time.monotonic()
        while True:
            self._poll()
            if watch is not None:
                watch()
            if self._q is not None and float(np.max(np.abs(self._q - goal))) < cfg.tolerance_rad:
                return
            now = time.monotonic()
            if now - t0 > cfg.move_timeout_s:
                err = float(np.max(np.abs(self.q - goal)))
                raise RosError(f"the arm did not reach {np.round(goal, 4).tolist()} within {cfg.move_timeout_s:g} s "
                               f"(still {err:.4f} rad away): expected every joint within {cfg.tolerance_rad} rad")
            if now - last >= cfg.republish_s:
                self._pub.write(msg)
                self.log("ur3hanoi: re-published the command (destination not reached yet)")
                last = now
            time.sleep(cfg.poll_s)

    def suction(self, on: bool) -> None:
        """Re-send the last commanded destination with ``io_0 = on`` (no motion) and wait until there."""
        self._io = bool(on)
        self.move(self._destination if self._destination is not None else self.q)
