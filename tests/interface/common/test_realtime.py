"""A server's real-time schedule: the lag of each cycle and its histogram, a step every period, the signals that
stop it or ask for a report."""

from __future__ import annotations

import os
import signal
import time

import pytest

from ur3hanoi.interface.common.realtime import LAG_BINS_MS, LoopTiming, RealTimeLoop


def test_loop_timing_counts_lag_into_its_histogram() -> None:
    t = LoopTiming(0.008)
    for lag_ms in (0.5, 1.5, 9.0, 100.0, -0.2):
        t.add(lag_ms / 1e3)
    d = t.as_dict(wall_s=0.04)
    assert d["cycles"] == 5 and d["late_cycles"] == 2 and d["publish_rate_hz"] == pytest.approx(125.0, abs=1e-9)
    assert d["worst_lag_s"] == pytest.approx(0.1, abs=1e-9)
    assert d["mean_lag_s"] == pytest.approx((0.5 + 1.5 + 9.0 + 100.0) / 5e3, abs=1e-6)
    hist = d["lag_histogram_ms"]
    assert list(hist) == [f"<{b:g}" for b in LAG_BINS_MS] + [f">={LAG_BINS_MS[-1]:g}"]
    assert hist["<1"] == 2 and hist["<2"] == 1 and hist["<16"] == 1 and hist[">=32"] == 1


def test_the_loop_keeps_its_period_and_stops_on_sigterm() -> None:
    """40 steps at 10 ms on the wall clock, a report on SIGUSR1, the stop on SIGTERM; the handlers restored."""
    loop = RealTimeLoop(0.01)
    steps: list[float] = []
    reports: list[int] = []

    def step() -> None:
        steps.append(time.perf_counter())
        if len(steps) == 10:
            os.kill(os.getpid(), signal.SIGUSR1)
        if len(steps) == 40:
            os.kill(os.getpid(), signal.SIGTERM)

    before = signal.getsignal(signal.SIGTERM)
    with loop.signals():
        loop.run(step, lambda: True, lambda: reports.append(len(steps)), duration_s=None)
    assert signal.getsignal(signal.SIGTERM) == before
    assert len(steps) == 40 and reports == [10]
    assert loop.timing.cycles == 40
    assert steps[-1] - steps[0] == pytest.approx(39 * 0.01, abs=0.2)  # the schedule is absolute: no drift
    assert loop.wall_s == pytest.approx(steps[-1] - loop.started, abs=0.05)


def test_the_loop_ends_after_its_duration_or_when_not_running() -> None:
    loop = RealTimeLoop(0.005)
    n = [0]

    def step() -> None:
        n[0] += 1

    loop.run(step, lambda: n[0] < 5, lambda: None, duration_s=None)
    assert n[0] == 5
    loop = RealTimeLoop(0.005)
    loop.run(step, lambda: True, lambda: None, duration_s=0.05)
    assert 0.05 <= loop.wall_s < 1.0
