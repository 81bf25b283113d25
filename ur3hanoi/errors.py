"""The exception hierarchy of ur3hanoi.

Every error a user can cause derives from :class:`Ur3HanoiError`. Messages are one line and name the bad value
and what would have been valid, so the CLI can print ``str(error)`` and exit with :attr:`Ur3HanoiError.exit_code`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # typing only: importing ur3hanoi.sim at run time would load MuJoCo and the planner
    from ur3hanoi.sim.result import SimResult


class Ur3HanoiError(Exception):
    """Base class of every user-facing error. The CLI prints it on one line and exits with ``exit_code``."""

    exit_code: int = 2


class CalibrationError(Ur3HanoiError):
    """A calibration (station) file is missing, malformed, or holds a value outside its valid range."""

    def __init__(self, source: str, field: str, value: object, allowed: str) -> None:
        self.source = source
        self.field = field
        self.value = value
        self.allowed = allowed
        super().__init__(f"{source}: field '{field}' = {value!r} is invalid: expected {allowed}")


class TableError(Ur3HanoiError):
    """A lab-format waypoint table (``lab2_data.yaml``) cannot be read or written."""


class IKError(Ur3HanoiError):
    """Inverse kinematics failed: the pose is unreachable, out of joint limits, or off the home branch."""


class TaughtPointsError(Ur3HanoiError):
    """A taught-points file, or a table used as taught points, cannot be used for calibration."""


class PuzzleError(Ur3HanoiError):
    """A Tower of Hanoi instance or move sequence is invalid (bad tower, too many blocks, illegal move)."""


class PlanError(Ur3HanoiError):
    """A motion plan violates a limit or a clearance, or could not be time-parameterized."""


class SimulationError(Ur3HanoiError):
    """The MuJoCo scene could not be built or run."""


class SuctionFaultError(Ur3HanoiError):
    """Suction feedback says no block is held where one should be (the lab's halt condition).

    Raised after the halt (arm stopped, suction off, arm home); ``result`` is the simulator's outcome of the run
    (status "halted") when the fault comes from :func:`ur3hanoi.sim.run_plan`, else None.
    """

    exit_code = 3

    def __init__(self, message: str, result: SimResult | None = None) -> None:
        super().__init__(message)
        self.result = result
