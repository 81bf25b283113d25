"""Is the arm still: no joint moved more than 0.05 deg over the last 0.5 s of published positions."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.teach.stillness import STALE_S, STILL_TOL_DEG, STILL_WINDOW_S, stillness

RATE_HZ = 125.0
NOW = 100.0
Q0 = np.radians([120.0, -90.0, 90.0, -90.0, -90.0, 0.0])


def published(offsets_deg: list[np.ndarray] | None = None, seconds: float = 1.0, end: float = NOW
              ) -> list[tuple[float, np.ndarray]]:
    """Positions at 125 Hz for ``seconds`` up to ``end``; the i-th of the last samples offset by ``offsets_deg``."""
    n = int(seconds * RATE_HZ)
    times = end - np.arange(n)[::-1] / RATE_HZ
    out = [(float(t), Q0.copy()) for t in times]
    for i, off in enumerate(offsets_deg or []):
        t, q = out[-1 - i]
        out[-1 - i] = (t, q + np.radians(off))
    return out


def test_a_steady_arm_is_still() -> None:
    s = stillness(published(), NOW)
    assert s.still and s.why == "" and s.moved_deg == 0.0


def test_a_joint_moving_more_than_the_tolerance_is_moving_and_named() -> None:
    off = np.zeros(6)
    off[3] = 0.2  # joint 4, in the last sample
    s = stillness(published([off]), NOW)
    assert not s.still
    assert math.isclose(s.moved_deg, 0.2, abs_tol=1e-9)
    assert "the arm is moving: joint 4 moved 0.20 deg" in s.why and f"{STILL_TOL_DEG:g} deg" in s.why


def test_motion_older_than_the_window_does_not_count() -> None:
    samples = published(seconds=2.0)
    t, q = samples[0]  # 2 s ago
    samples[0] = (t, q + np.radians(5.0))
    assert stillness(samples, NOW).still


def test_the_tolerance_is_the_stated_one() -> None:
    for moved, still in ((STILL_TOL_DEG * 0.99, True), (STILL_TOL_DEG * 1.01, False)):
        off = np.zeros(6)
        off[0] = moved
        assert stillness(published([off]), NOW).still is still


def test_no_recent_position_is_not_still() -> None:
    s = stillness(published(end=NOW - 2 * STALE_S), NOW)
    assert not s.still and math.isnan(s.moved_deg) and "no position" in s.why
    assert not stillness([], NOW).still


def test_less_than_the_window_of_positions_is_not_still_yet() -> None:
    s = stillness(published(seconds=STILL_WINDOW_S / 3), NOW)
    assert not s.still and "not in yet" in s.why


@settings(max_examples=50, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_noise_within_half_the_tolerance_is_still(seed: int) -> None:
    rng = np.random.default_rng(seed)
    noise = [rng.uniform(-0.25, 0.25, 6) * STILL_TOL_DEG for _ in range(int(RATE_HZ))]
    assert stillness(published(noise), NOW).still
