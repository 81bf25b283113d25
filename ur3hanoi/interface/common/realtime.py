"""A server's real-time schedule: one step per control period on the wall clock, the lag of each, and the signals
that stop it (SIGINT, SIGTERM) or ask for a report (SIGUSR1).

The schedule is absolute: a late cycle is caught up by the following ones, so world time never drifts from wall
time; the lag of every cycle's start behind its schedule is measured (:class:`LoopTiming`).
"""

from __future__ import annotations

import bisect
import gc
import signal
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType
from typing import Any

LAG_BINS_MS: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""Upper edges [ms] of the loop-lag histogram in the report (a last bin counts the rest)."""


class LoopTiming:
    """Lag of each control cycle's start behind its wall-clock schedule [s], and a histogram of it."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self.cycles = 0
        self.worst_lag_s = 0.0
        self.last_lag_s = 0.0
        self.total_lag_s = 0.0
        self.late_cycles = 0  # started more than one period late
        self.histogram = [0] * (len(LAG_BINS_MS) + 1)

    def add(self, lag_s: float) -> None:
        self.cycles += 1
        self.last_lag_s = lag_s
        self.total_lag_s += max(0.0, lag_s)
        self.worst_lag_s = max(self.worst_lag_s, lag_s)
        if lag_s > self.period_s:
            self.late_cycles += 1
        self.histogram[bisect.bisect_right(LAG_BINS_MS, 1e3 * lag_s)] += 1

    def as_dict(self, wall_s: float) -> dict[str, Any]:
        return {"rate_hz": round(1.0 / self.period_s, 3), "period_s": self.period_s, "cycles": self.cycles,
                "publish_rate_hz": round(self.cycles / wall_s, 2) if wall_s > 0 else None,
                "worst_lag_s": round(self.worst_lag_s, 6),
                "mean_lag_s": round(self.total_lag_s / self.cycles, 6) if self.cycles else None,
                "late_cycles": self.late_cycles,
                "lag_histogram_ms": {**{f"<{b:g}": n for b, n in zip(LAG_BINS_MS, self.histogram, strict=False)},
                                     f">={LAG_BINS_MS[-1]:g}": self.histogram[-1]}}


class RealTimeLoop:
    """Runs a step every ``period_s`` [s] of wall time until stopped (see the module docstring)."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self.timing = LoopTiming(period_s)
        self._stop = False
        self._dump = False
        self._wall0 = 0.0
        self._wall_end: float | None = None

    @property
    def wall_s(self) -> float:
        """Wall time [s] the loop has run (0 before it starts)."""
        return (self._wall_end or time.perf_counter()) - self._wall0 if self._wall0 else 0.0

    @property
    def started(self) -> float:
        """``time.perf_counter()`` when the loop started (0 before)."""
        return self._wall0

    def _signal(self, signum: int, _frame: FrameType | None) -> None:
        if signum == signal.SIGUSR1:
            self._dump = True
        else:
            self._stop = True

    @contextmanager
    def signals(self) -> Iterator[None]:
        """SIGINT/SIGTERM stop :meth:`run`, SIGUSR1 asks for a report; the previous handlers are restored after."""
        handled = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
        previous = {s: signal.signal(s, self._signal) for s in handled}
        try:
            yield
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)

    def run(self, step: Callable[[], None], running: Callable[[], bool], report: Callable[[], object],
            duration_s: float | None) -> None:
        """``step()`` every period, ``report()`` on SIGUSR1, until stopped, ``running()`` is false or
        ``duration_s`` [s] passed."""
        # Everything built so far lives as long as the node: keep the cyclic collector from scanning it in the loop.
        gc.collect()
        gc.freeze()
        self._wall0 = next_t = time.perf_counter()
        try:
            while not self._stop and running():
                now = time.perf_counter()
                self.timing.add(now - next_t)
                step()
                if self._dump:
                    self._dump = False
                    report()
                if duration_s is not None and now - self._wall0 >= duration_s:
                    break
                next_t += self.period_s
                delay = next_t - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
        finally:
            self._wall_end = time.perf_counter()
