"""teach on the official UR driver (``teach --driver ur``): what the session adds there.

The recording is the same as on the course's topics (the published pose, by joint name, when the arm is still); what
differs is motion and suction:

- the External Control program's state: recording needs no program (freedrive or the pendant's jog move the arm),
  jogging does: a jog key while the program is stopped is refused with that reason, and a jog goal the controller
  rejects or aborts is named (its code and text) instead of waiting for the arm;
- ``v`` switches the suction on or off through ``set_io`` on the calibration's output and reads it back from
  ``io_states`` (is a block held on the taught pose?); the session switches it off at its end.

The driver is a :class:`UrDriver` (:class:`ur3hanoi.interface.urdriver.cell.DriverArm` on ROS 1 or ROS 2); the command
line connects it and hands it in, as for the course's topics. This module imports no middleware.
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Collection
from typing import Protocol

from ur3hanoi.errors import DriverError
from ur3hanoi.station.calibration import Station
from ur3hanoi.teach.driver import Driver, DriverNames
from ur3hanoi.teach.jog import JogTarget
from ur3hanoi.teach.session import ARRIVAL_MARGIN_S, Teacher
from ur3hanoi.teach.taught_file import TaughtFile

GOAL_WAIT_S = 60.0
"""[s] the longest a jog goal without a result is waited for (a 20 mm step takes about 1 s at a slider of 100 %)."""
SUCTION_KEY = "v"
"""The key that switches the suction (vacuum) on or off."""


class UrDriver(Driver, Protocol):
    """A :class:`~ur3hanoi.teach.driver.Driver` on the official UR driver (see the module docstring)."""

    def program_running(self) -> bool | None:
        """The driver's ``robot_program_running`` (None: not known yet)."""
        ...

    def jog_problem(self) -> str:
        """Why a jog goal cannot be sent now ("" when it can)."""
        ...

    def goal_running(self) -> bool:
        """True while the last jog goal has no result."""
        ...

    def goal_problem(self) -> str:
        """How the last jog goal failed, said once ("" while it runs or when it succeeded)."""
        ...

    def suction(self, on: bool) -> str:
        """Switch the suction, wait for ``io_states`` to show it and say what it reads (DriverError if it does
        not)."""
        ...


def ur_names(where: str, ros: str) -> DriverNames:
    """How messages name the official driver on ``ros`` (``ros`` or ``ros2``)."""
    return DriverNames(where, "/joint_states", "the scaled trajectory controller's follow_joint_trajectory",
                       f"{ros}-solve")


def program_line(driver: UrDriver) -> str:
    """What the session says about the program when it starts."""
    running = driver.program_running()
    if running is None:
        return "the driver has not said whether the External Control program runs: jog keys will tell"
    if running:
        return "the External Control program runs: jog keys send short trajectory goals at 20 deg/s"
    return ("the External Control program is stopped: record with freedrive; start it on the pendant to jog with "
            "the keys")


class UrTeacher(Teacher):
    """A :class:`~ur3hanoi.teach.session.Teacher` on the official UR driver (see the module docstring)."""

    driver: UrDriver

    def __init__(self, base: Station, base_label: str, taught: TaughtFile, driver: UrDriver, names: DriverNames,
                 start: int, accept: Collection[tuple[int, int]] = ()) -> None:
        super().__init__(base, base_label, taught, driver, names, start, accept)
        self.suction_on = False
        self.move_started = 0.0  # [s, monotonic] when the running jog goal was sent
        self.extra_help = (f"{SUCTION_KEY} suction on/off through set_io on DO{base.wiring.output}, read back from "
                           f"io_states (DI{base.wiring.switch_input} = 1: a block is held); jogging needs the External "
                           "Control program, recording does not",)

    def _motion_allowed(self) -> list[str] | None:
        problem = self.driver.jog_problem()
        if problem:
            return [problem]
        return super()._motion_allowed()

    def tick(self) -> list[str]:
        if self.move is not None and self.driver.goal_running() and time.monotonic() < self.move_started + GOAL_WAIT_S:
            # The goal's own time runs with the pendant's slider: wait for its result, not for the jog caps' time.
            self.move = dataclasses.replace(self.move, deadline=time.monotonic() + ARRIVAL_MARGIN_S)
        lines = super().tick()
        problem = self.driver.goal_problem()
        if problem and self.move is not None:
            what, self.move = self.move.what, None
            lines.append(f"{what}: {problem}")
        return lines

    def _send(self, target: JogTarget, what: str) -> list[str]:
        self.move_started = time.monotonic()
        return super()._send(target, what)

    def other_key(self, ch: str) -> list[str] | None:
        if ch != SUCTION_KEY:
            return None
        try:
            said = self.driver.suction(not self.suction_on)
        except DriverError as exc:
            return [f"suction: {exc}"]
        self.suction_on = not self.suction_on
        return [said]


__all__ = ["GOAL_WAIT_S", "SUCTION_KEY", "UrDriver", "UrTeacher", "program_line", "ur_names"]
