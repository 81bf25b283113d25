"""Log lines that a flood of messages cannot multiply: at most one line per topic and interval.

A publisher flooding ``ur3/command`` at 1 kHz with refused commands used to write one log line per message (1.4 MB
in seconds, to stderr, the node's log file and ``/rosout``). :class:`RateLimitedLog` writes the first line of a
quiet topic at once; what follows within :attr:`interval_s` of the last line is counted and written as one summary
line when the interval has passed (:meth:`flush`, called every control cycle, and at shutdown with ``force``): the
number of messages and their most frequent reasons. Nothing here knows ROS: ``emit(level, text)`` writes a line.
"""

from __future__ import annotations

import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

LEVELS = ("info", "warn", "error")
"""Levels in increasing severity; a summary takes the worst level it covers."""


@dataclass
class _Topic:
    last_emit: float
    level: str = "info"
    pending: int = 0
    reasons: Counter[str] = field(default_factory=Counter)
    other: int = 0  # pending messages whose reason did not fit into ``reasons``


class RateLimitedLog:
    """At most one line per ``topic`` and ``interval_s`` [s] (see the module docstring).

    Args:
        emit: writes one line at a level of :data:`LEVELS`.
        interval_s: least time between two lines of a topic [s].
        max_reasons: distinct reasons a summary names (the rest are counted as "other").
        clock: monotonic clock [s].
    """

    def __init__(self, emit: Callable[[str, str], None], interval_s: float = 1.0, max_reasons: int = 4,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.emit = emit
        self.interval_s = interval_s
        self.max_reasons = max_reasons
        self.clock = clock
        self.lines = 0
        self._topics: dict[str, _Topic] = {}

    def log(self, topic: str, level: str, reason: str) -> None:
        """One message of ``topic`` (the line's prefix) with its ``reason``: written now, or counted."""
        now = self.clock()
        t = self._topics.get(topic)
        if t is None or (t.pending == 0 and now - t.last_emit >= self.interval_s):
            self._topics[topic] = _Topic(now)
            self._write(level, f"{topic}: {reason}")
            return
        t.pending += 1
        if LEVELS.index(level) > LEVELS.index(t.level):
            t.level = level
        if reason in t.reasons or len(t.reasons) < self.max_reasons:
            t.reasons[reason] += 1
        else:
            t.other += 1

    def flush(self, force: bool = False) -> None:
        """Write the summary of every topic whose interval has passed (all of them with ``force``)."""
        now = self.clock()
        for topic, t in self._topics.items():
            if t.pending and (force or now - t.last_emit >= self.interval_s):
                parts = [f"{n} x {reason}" for reason, n in t.reasons.most_common()]
                if t.other:
                    parts.append(f"{t.other} x other reasons")
                self._write(t.level, f"{topic}: {t.pending} more in the last {now - t.last_emit:.1f} s: "
                                     + "; ".join(parts))
                self._topics[topic] = _Topic(now)

    def _write(self, level: str, text: str) -> None:
        self.lines += 1
        self.emit(level, text)
