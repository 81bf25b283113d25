"""A number's valid range: the one range type of the input files' schemas and of the command-line options.

:class:`Number` says what a field or an option accepts (a finite number, or an integer, in a range with a unit) and
how a message names it (``a sample rate [Hz] in [1, 10000]``). It lives apart from :mod:`ur3hanoi.io.schema` so that
building the ``ur3hanoi`` parser, which needs every option's range, imports nothing else: no dataclasses (whose
import, through :mod:`inspect`, is a sixth of a ``--help``), no validator.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple


def format_bound(x: float) -> str:
    """``0.2``, ``360``, ``4294967295`` (whole numbers in full, others shortest)."""
    if float(x).is_integer() and abs(x) < 1e16:
        return str(int(x))
    return f"{x:g}"


class Number(NamedTuple):
    """A finite number (or an integer) in a range. ``unit`` is shown in messages (``"m"`` -> ``[m]``).

    Immutable and compared by value (a NamedTuple rather than a frozen dataclass only for the start-up time, see
    the module docstring)."""

    lo: float = -math.inf
    hi: float = math.inf
    lo_open: bool = False
    hi_open: bool = False
    unit: str = ""
    integer: bool = False
    what: str = ""

    def expected(self) -> str:
        """What is allowed, for a message: ``a length [m] in (0, 0.2]``, ``an integer``, ``a finite number``."""
        noun = self.what or ("an integer" if self.integer else "a number")
        unit = f" [{self.unit}]" if self.unit else ""
        if math.isinf(self.lo) and math.isinf(self.hi):
            return f"{noun}{unit}" if self.integer else f"a finite {noun.split(' ', 1)[-1]}{unit}"
        lo = "(" if self.lo_open or math.isinf(self.lo) else "["
        hi = ")" if self.hi_open or math.isinf(self.hi) else "]"
        return f"{noun}{unit} in {lo}{format_bound(self.lo)}, {format_bound(self.hi)}{hi}"

    def accepts(self, value: Any) -> bool:
        """True for a finite number (an int if ``integer``) inside the range; never for a bool."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            return False
        if self.integer and not isinstance(value, int):
            return False
        x: float | int = value
        if not isinstance(value, int) or not self.integer:
            try:
                x = float(value)
            except OverflowError:  # an int too large for a float is outside any finite range
                return False
            if not math.isfinite(x):
                return False
        return not (x < self.lo or x > self.hi or (self.lo_open and x == self.lo) or (self.hi_open and x == self.hi))
