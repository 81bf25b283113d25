"""The exception hierarchy of ur3hanoi.

Every error a user can cause derives from :class:`Ur3HanoiError`. Messages are one line, name the bad value and
what would have been valid, and never mention command-line flags: the command line (:mod:`ur3hanoi.cli`) maps the
classes to exit codes. Values and paths quoted in a message go through :func:`quote` and :func:`printable`, so a
hostile input (a megabyte string, a recursive list, a path with newlines or escape sequences) cannot flood or break
the message.

Hierarchy::

    Ur3HanoiError
    +-- InputError              an input file or value is unusable (unreadable, malformed, fails its schema)
    |   +-- CalibrationError    a station calibration file
    |   +-- TaughtPointsError   a taught-points file (or a table used as taught points)
    |   +-- TableError          a lab-format waypoint table (lab2_data.yaml)
    +-- OutputError             an output path cannot be written safely (nothing was written)
    +-- DriverError             the arm's driver stopped or publishes what no UR driver does (``teach``)
    +-- IKError, PuzzleError, PlanError, SimulationError
    +-- SuctionFaultError       suction feedback says no block is held (the lab's halt condition)

A :class:`Ur3HanoiWarning` (:mod:`warnings`) says something the user should know without stopping anything (the
command line prints it as ``ur3hanoi: warning: ...``).
"""

from __future__ import annotations

import reprlib
from typing import Any, Self

MAX_QUOTE_CHARS = 60
"""Longest quoted value (or path) in an error message [characters]; longer ones are cut with ``...``."""

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxtuple, _REPR.maxlist, _REPR.maxdict, _REPR.maxset = 3, 6, 6, 4, 4
_REPR.maxstring, _REPR.maxlong, _REPR.maxother = MAX_QUOTE_CHARS, 40, MAX_QUOTE_CHARS


def printable(text: object, limit: int = 4 * MAX_QUOTE_CHARS) -> str:
    """``text`` with every non-printable character escaped (``\\n``, ``\\x1b``, surrogates...), cut at ``limit``.

    Used for paths and labels echoed in messages and in generated file headers: they stay on one line, cannot
    inject terminal escape sequences or YAML line breaks, and always encode as UTF-8.
    """
    s = str(text)
    if not s.isprintable():
        s = "".join(c if c.isprintable() else c.encode("unicode_escape").decode("ascii") for c in s)
    return s if len(s) <= limit else s[: limit - 3] + "..."


def quote(value: object) -> str:
    """A short ``repr`` of ``value`` for an error message (at most about :data:`MAX_QUOTE_CHARS` characters)."""
    try:
        s = _REPR.repr(value)
    except Exception:  # a broken __repr__ must not turn a clean error into a crash
        s = f"<{type(value).__name__}>"
    return printable(s, MAX_QUOTE_CHARS + 20)


class Ur3HanoiError(Exception):
    """Base class of every user-facing error: one line, names the bad value and the valid alternatives."""

    exit_code: int = 2
    """Exit status recorded in :class:`ur3hanoi.sim.SimResult` (the command line's own mapping of classes to exit
    codes is :data:`ur3hanoi.cli.exit_codes.EXIT_CODES`)."""


MISSING: Any = type("Missing", (), {"__repr__": lambda self: "<missing>"})()
"""Sentinel for :meth:`InputError.invalid`: the field is absent."""


class InputError(Ur3HanoiError):
    """An input file or value is unusable. ``source``, ``field``, ``value`` and ``allowed`` say which and why."""

    def __init__(self, message: str, *, source: str = "", field: str = "", value: object = None,
                 allowed: str = "") -> None:
        super().__init__(message)
        self.source = source
        self.field = field
        self.value = value
        self.allowed = allowed

    @classmethod
    def invalid(cls, source: str, field: str, value: object, allowed: str) -> Self:
        """``<source>: field '<field>' = <value> is invalid: expected <allowed>`` (or ``... is missing: ...``)."""
        where = f"{printable(source)}: field '{printable(field, MAX_QUOTE_CHARS)}'"
        if value is MISSING:
            message = f"{where} is missing: expected {allowed}"
        else:
            message = f"{where} = {quote(value)} is invalid: expected {allowed}"
        return cls(message, source=source, field=field, value=value, allowed=allowed)

    @classmethod
    def file(cls, source: str, problem: str) -> Self:
        """``<source>: <problem>`` for a file that cannot be read or parsed at all."""
        return cls(f"{printable(source)}: {problem}", source=source, field="<file>")


class CalibrationError(InputError):
    """A calibration (station) file is missing, malformed, or holds a value outside its valid range."""


class TaughtPointsError(InputError):
    """A taught-points file, or a table used as taught points, cannot be used for calibration."""


class TableError(InputError):
    """A lab-format waypoint table (``lab2_data.yaml``) cannot be read, checked or updated."""


class OutputError(Ur3HanoiError):
    """An output path cannot be written safely (a directory, a device, an input file, no space...).

    Raised before anything is written, or after a failed write that was rolled back: the old file, if any, is
    byte-identical and no temporary file is left behind.
    """


class DriverError(Ur3HanoiError):
    """The arm's driver (the course's, or ur3hanoi's server) cannot be reached, stopped publishing, did not reach a
    commanded pose in time, or publishes what no UR driver does (not six finite joint angles). A solve stops (exit
    2); a teach session stops with what was recorded saved. Each binding's middleware failures are subclasses
    (``ur3hanoi.interface.ros1.errors.RosError``, ``ur3hanoi.interface.ros2.errors.DdsError``)."""


class ProgramStoppedError(DriverError):
    """The robot's External Control program stopped during a solve (the pendant's stop button, a protective stop):
    the driver stopped its trajectory controller with it, the arm stopped where it was. Exit 3, as a halt."""

    exit_code = 3


class IKError(Ur3HanoiError):
    """Inverse kinematics failed: the pose is unreachable, out of joint limits, or off the home branch."""


class PuzzleError(Ur3HanoiError):
    """A Tower of Hanoi instance or move sequence is invalid (bad tower, too many blocks, illegal move)."""


class PlanError(Ur3HanoiError):
    """A motion plan violates a limit or a clearance, or could not be time-parameterized."""


class SimulationError(Ur3HanoiError):
    """The MuJoCo scene could not be built or run."""


class SuctionFaultError(Ur3HanoiError):
    """Suction feedback says no block is held where one should be (the lab's halt condition).

    Raised after the halt (arm stopped, suction off, arm home); ``result`` is the simulator's outcome of the run
    (a :class:`ur3hanoi.sim.SimResult`, status "halted") when the fault comes from :func:`ur3hanoi.sim.run_plan`,
    else None. It is typed ``object`` because this module is the bottom of the package: it imports nothing of
    ur3hanoi, so every module can import it without a cycle.
    """

    exit_code = 3

    def __init__(self, message: str, result: object | None = None) -> None:
        super().__init__(message)
        self.result = result


class Ur3HanoiWarning(UserWarning):
    """Something the user should know that stops nothing (one line, like an error's message)."""
