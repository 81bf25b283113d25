"""The official UR driver seen by the commands that run before a solve (``teach --driver ur``, ``check-arm``): the
arm as teach's driver, jogged by short trajectory goals, the suction switched and read back, the program's state.

- :class:`JointHistory` is the transport's joint record kept as a ring of the last :data:`HISTORY_S` seconds (every
  ``/joint_states`` the binding receives, by name into the controller's order), with the count received: teach judges
  stillness on it, the check measures the driver's publishing rate from it.
- :class:`CellLink` is what a binding adds to its :class:`~ur3hanoi.interface.urdriver.client.DriverTransport` for
  these commands: the External Control program's state (the drivers' latched ``robot_program_running``) and whether
  the driver is ur3hanoi's own stand-in (no pendant there). ROS 1: :mod:`ur3hanoi.interface.ros1.ur_cell`; ROS 2:
  :mod:`ur3hanoi.interface.ros2.ur_cell`.
- :class:`DriverArm` is teach's driver (:class:`ur3hanoi.teach.driver.Driver`, and the extra of
  :class:`ur3hanoi.teach.ur_driver.UrDriver`) on a connected link: recording needs only the joint states (freedrive
  or the pendant's jog move the arm); a jog step is one rest-to-rest goal at teach's slow speed through the scaled
  controller, refused with the reason while the program is stopped; the suction is switched with ``set_io`` on the
  calibration's output and read back from ``io_states``.
"""

from __future__ import annotations

import threading
import time
from collections import deque
from typing import Protocol

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import DriverError
from ur3hanoi.interface.urdriver.client import DriverTransport, GoalHandle
from ur3hanoi.interface.urdriver.facts import FUN_SET_DIGITAL_OUT
from ur3hanoi.interface.urdriver.joint_record import JointRecord
from ur3hanoi.interface.urdriver.plan_goals import move_goal
from ur3hanoi.station.calibration import Station

HISTORY_S = 3.0
"""[s] how much of the joint states :class:`JointHistory` keeps."""
IO_READBACK_S = 1.0
"""[s] how long the suction's output and vacuum switch are given to show in ``io_states`` after ``set_io``."""
PROGRAM_STOPPED = ("the External Control program is not running on the pendant (start it: Program > URCaps > "
                   "External Control, press play)")
"""Why a motion is refused while the program is stopped."""


class JointHistory(JointRecord):
    """A :class:`JointRecord` that also keeps every joint state of the last :data:`HISTORY_S` seconds and counts
    them, recording or not (the transport calls :meth:`add` from its callback thread)."""

    def __init__(self) -> None:
        super().__init__(capacity=2)
        self._ring: deque[tuple[float, FloatArray]] = deque()
        self._ring_lock = threading.Lock()
        self.count = 0
        """Joint states received since this history was made."""

    def add(self, t: float, q: FloatArray) -> None:
        with self._ring_lock:
            self.count += 1
            self._ring.append((t, np.array(q, dtype=float)))
            while self._ring and self._ring[0][0] < t - HISTORY_S:
                self._ring.popleft()

    def window(self, window_s: float) -> list[tuple[float, FloatArray]]:
        """The joint states of the last ``window_s`` seconds: (time of arrival [s, monotonic], q [rad]), oldest
        first."""
        now = time.monotonic()
        with self._ring_lock:
            return [(t, q) for t, q in self._ring if t >= now - window_s]


class CellLink(DriverTransport, Protocol):
    """A :class:`~ur3hanoi.interface.urdriver.client.DriverTransport` with what the commands before a solve need."""

    history: JointHistory
    action: str
    """The trajectory controller's action (``/scaled_pos_joint_traj_controller/follow_joint_trajectory``)."""

    def program_running(self) -> bool | None:
        """The driver's latched ``robot_program_running`` (None: nothing received yet)."""

    def controller_state(self) -> str | None:
        """The scaled trajectory controller's state from the controller manager (``active``, ``inactive``, ``not
        loaded``), None when it cannot be asked."""

    def simulated(self) -> bool:
        """True for ur3hanoi's own ``ros-station --driver ur`` / ``ros2-station --driver ur`` (no pendant)."""


def jog_speed_fraction(station: Station, v_rad_s: float, a_rad_s2: float) -> float:
    """The fraction of ``station``'s limits at which no joint exceeds ``v_rad_s`` [rad/s] nor ``a_rad_s2``
    [rad/s^2] (a goal from :func:`~ur3hanoi.interface.urdriver.plan_goals.move_goal` scales all three limits)."""
    lim = station.limits
    return float(min(1.0, v_rad_s / max(lim.v_max), a_rad_s2 / max(lim.a_max)))


def suction_text(link: DriverTransport, station: Station) -> str:
    """``DO1=1 DI0=0 AI0=1.40 V``: the suction's output, vacuum switch and sensor as ``io_states`` shows them."""
    io, w = link.latest().io, station.wiring
    if io is None:
        return "no io_states"
    return (f"DO{w.output}={int(io.digital_out[w.output])} DI{w.switch_input}={int(io.digital_in[w.switch_input])} "
            f"AI{w.sensor_input}={io.analog_in[w.sensor_input][1]:.2f} V")


def suction_outputs(station: Station) -> tuple[int, ...]:
    """The outputs the suction needs on, in the order they are switched on: the vacuum generator's first where the
    calibration names one (``io.vacuum_generator_output``), then the cup's; off in the reverse order."""
    return station.wiring.outputs


def switch_suction(link: DriverTransport, station: Station, on: bool) -> str:
    """``set_io`` on the calibration's suction outputs (:func:`suction_outputs`), then wait (at most
    :data:`IO_READBACK_S`) until ``io_states`` shows them; returns what ``io_states`` shows.

    Raises:
        DriverError: ``set_io`` answered ``success = false``, or an output did not show in ``io_states``.
    """
    pins = suction_outputs(station)
    for pin in pins if on else pins[::-1]:
        if not link.set_io(FUN_SET_DIGITAL_OUT, pin, 1.0 if on else 0.0):
            raise DriverError(f"set_io(fun={FUN_SET_DIGITAL_OUT}, pin={pin}, state={int(on)}) answered success = "
                              f"false on {link.where}: is the calibration's io section right and the robot program "
                              "running?")
    end = time.monotonic() + IO_READBACK_S
    while time.monotonic() < end:
        io = link.latest().io
        if io is not None and all(io.digital_out[pin] == on for pin in pins):
            return suction_text(link, station)
        link.wait(0.02)
    raise DriverError(f"set_io answered success but io_states does not show DO{'/'.join(map(str, pins))}="
                      f"{int(on)} after {IO_READBACK_S:g} s on {link.where}")


class DriverArm:
    """teach's driver on the official UR driver (see the module docstring).

    Args:
        link: the connected binding.
        station: the base calibration (limits for the jog goals, the suction's wiring).
    """

    malformed = ""  # the binding drops a joint state without the six joints: teach then sees it as silence

    def __init__(self, link: CellLink, station: Station) -> None:
        self.link, self.station = link, station
        self.goal: GoalHandle | None = None
        self.suction_on = False
        self._simulated = link.simulated()

    # ------------------------------------------------------------------------------------- teach.driver.Driver
    def samples(self, window_s: float) -> list[tuple[float, FloatArray]]:
        return self.link.history.window(window_s)

    def send(self, q: FloatArray, v: float, a: float) -> None:
        """One rest-to-rest goal from the published pose to ``q`` [rad] at most ``v`` [rad/s], ``a`` [rad/s^2]."""
        problem = self.jog_problem()
        if problem:
            raise DriverError(problem)
        q0 = self.link.latest().q
        if q0 is None:
            raise DriverError(f"no joint states from the driver on {self.link.where}")
        self.goal = self.link.send_goal(move_goal(q0, np.asarray(q, dtype=float), self.station,
                                                  jog_speed_fraction(self.station, v, a)))

    def simulated(self) -> bool:
        return self._simulated

    # ------------------------------------------------------------------------------------------- the UR extras
    def program_running(self) -> bool | None:
        return self.link.program_running()

    def jog_problem(self) -> str:
        """Why a jog step cannot be sent now ("" when it can)."""
        if self.link.program_running() is False:
            return f"jog refused: {PROGRAM_STOPPED}; recording needs no program (move the arm in freedrive)"
        return ""

    def goal_running(self) -> bool:
        """True while the last jog goal has no result (the controller's time runs with the speed slider)."""
        return self.goal is not None and not self.goal.done()

    def goal_problem(self) -> str:
        """How the last jog goal failed, once ("" while it runs or when it succeeded)."""
        goal = self.goal
        if goal is None or not goal.done():
            return ""
        self.goal = None
        result = goal.result()
        return "" if result.status == "succeeded" else f"the driver's controller {result.describe()}"

    def suction(self, on: bool) -> str:
        """Switch the suction and say what ``io_states`` reads back (raises DriverError when it does not)."""
        text = switch_suction(self.link, self.station, on)
        self.suction_on = on
        held = self.link.latest().io
        w = self.station.wiring
        state = ("a block is held (the vacuum switch reads 1)" if held is not None and held.digital_in[w.switch_input]
                 else "no block held (the vacuum switch reads 0)") if on else "off"
        return f"suction {'on' if on else 'off'}: {text}: {state}"

    def close(self) -> None:
        """Suction off if teach switched it on (the cup must not hold a block after the session), then disconnect."""
        try:
            if self.suction_on:
                for pin in suction_outputs(self.station)[::-1]:
                    self.link.set_io(FUN_SET_DIGITAL_OUT, pin, 0.0)
        finally:
            self.link.close()


__all__ = ["HISTORY_S", "IO_READBACK_S", "PROGRAM_STOPPED", "CellLink", "DriverArm", "JointHistory",
           "jog_speed_fraction", "suction_outputs", "suction_text", "switch_suction"]
