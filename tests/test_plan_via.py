"""Via-speed candidates and the (exit, entry) search (ur3hanoi.plan.via), on synthetic costs."""

from __future__ import annotations

import itertools
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.plan.via import Leg, LegCandidates, best_via_pair


def _candidates(n: int, infeasible: frozenset[int] = frozenset()) -> tuple[LegCandidates, list[float]]:
    """n candidates with speeds n-1 .. 0 and duration 10 - sigma; ``infeasible`` speeds are dropped."""
    calls: list[float] = []

    def solve(sigma: float) -> float | None:
        calls.append(sigma)
        return None if sigma in infeasible else 10.0 - sigma

    return LegCandidates([float(s) for s in range(n - 1, -1, -1)], solve), calls


def test_candidates_are_solved_lazily_and_failures_dropped() -> None:
    legs, calls = _candidates(5, frozenset({3.0}))
    assert legs.get(0) == Leg(4.0, 6.0) and calls == [4.0]
    assert legs.get(1) == Leg(2.0, 8.0) and calls == [4.0, 3.0, 2.0]
    assert legs.count() == 4 and legs.get(4) is None
    assert LegCandidates.at_rest().count() == 1 and LegCandidates.at_rest().get(0) == Leg(0.0, 0.0)


@settings(max_examples=50, deadline=None)
@given(n0=st.integers(1, 6), n1=st.integers(1, 6), a=st.floats(0, 5), b=st.floats(0, 5))
def test_descent_finds_the_minimum_of_a_separable_convex_grid(n0: int, n1: int, a: float, b: float) -> None:
    exits, _ = _candidates(n0)
    entries, _ = _candidates(n1)

    def cost(i: int, j: int) -> float:
        return (i - a) ** 2 + (j - b) ** 2  # separable convex: a 4-neighbour local minimum is global

    best = min(itertools.product(range(n0), range(n1)), key=lambda ij: cost(*ij))
    assert cost(*best_via_pair(exits, entries, cost)) == cost(*best)


def test_all_pairs_are_tried_when_nothing_near_the_fastest_pair_is_feasible() -> None:
    exits, _ = _candidates(6)
    entries, _ = _candidates(6)
    evaluated: set[tuple[int, int]] = set()

    def cost(i: int, j: int) -> float:
        evaluated.add((i, j))
        return float(i + j) if (i, j) == (5, 4) else math.inf

    assert best_via_pair(exits, entries, cost) == (5, 4)
    assert len(evaluated) == 36


def test_infeasible_everywhere_returns_an_infeasible_pair() -> None:
    exits, _ = _candidates(2)
    entries, _ = _candidates(3)
    i, j = best_via_pair(exits, entries, lambda i, j: math.inf)
    assert 0 <= i < 2 and 0 <= j < 3
