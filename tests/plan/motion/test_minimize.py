"""The Nelder-Mead minimiser (plan.motion.minimize, SciPy): minimum, stopping rules, infeasible points, determinism."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.plan.motion.minimize import nelder_mead


@settings(max_examples=30, deadline=None, derandomize=True)
@given(cx=st.floats(-3, 3), cy=st.floats(-3, 3), scale=st.floats(0.1, 10))
def test_minimises_a_quadratic(cx: float, cy: float, scale: float) -> None:
    r = nelder_mead(lambda x: scale * ((x[0] - cx) ** 2 + 3 * (x[1] - cy) ** 2), [0.0, 0.0], [0.5, 0.5],
                    max_evals=400, x_tol=1e-8)
    assert r.x == pytest.approx((cx, cy), abs=1e-5)
    assert r.evaluations <= 400 + 3  # the last step may take up to n + 1 evaluations


def test_stops_at_the_target_and_at_the_budget() -> None:
    calls = []

    def f(x: list[float] | tuple[float, ...]) -> float:
        calls.append(1)
        return (x[0] - 1.0) ** 2

    r = nelder_mead(f, [0.0], [0.1], f_target=0.01)
    assert r.fun <= 0.01 and r.evaluations == len(calls) < 30
    calls.clear()
    r = nelder_mead(f, [0.0], [1e-6], max_evals=7)
    assert r.evaluations == len(calls) and 7 <= r.evaluations <= 8  # a shrink step may finish its simplex


def test_infeasible_points_are_avoided_and_results_repeat() -> None:
    def f(x: list[float] | tuple[float, ...]) -> float:
        return math.inf if x[0] < 0.5 else (x[0] - 0.7) ** 2 + x[1] ** 2

    a = nelder_mead(f, [1.0, 1.0], [0.2, 0.2], max_evals=300)
    b = nelder_mead(f, [1.0, 1.0], [0.2, 0.2], max_evals=300)
    assert a == b and a.x[0] >= 0.5 and a.fun < 1e-6
