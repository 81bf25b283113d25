"""Exit codes of the ``ur3hanoi`` command, and which exception class maps to which.

====  ==========================================================================================
0     success
1     ``check-table``: some entry is over the tolerance
2     bad input: an invalid file, option or output path, an unreachable pose, a failed plan check
3     halted: a suction fault in a solve (suction off, arm at home), or the robot program stopped in one
70    internal error (a bug: rerun with ``--debug`` for the traceback)
130   interrupted (Ctrl-C)
143   terminated (SIGTERM: the same clean-up as a Ctrl-C)
141   standard output closed early (e.g. piped into ``head``)
====  ==========================================================================================
"""

from __future__ import annotations

from ur3hanoi.errors import ProgramStoppedError, SuctionFaultError, Ur3HanoiError

OK = 0
OVER_TOLERANCE = 1
BAD_INPUT = 2
SUCTION_FAULT = 3
INTERNAL = 70
INTERRUPTED = 130
TERMINATED = 143
BROKEN_PIPE = 141

EXIT_CODES: tuple[tuple[type[Ur3HanoiError], int], ...] = (
    (SuctionFaultError, SUCTION_FAULT),
    (ProgramStoppedError, SUCTION_FAULT),
    (Ur3HanoiError, BAD_INPUT),
)
"""Library exception classes and their exit codes, most specific first."""


def exit_code_for(error: Ur3HanoiError) -> int:
    """The exit code of a library error (the first matching class of :data:`EXIT_CODES`)."""
    return next(code for cls, code in EXIT_CODES if isinstance(error, cls))
