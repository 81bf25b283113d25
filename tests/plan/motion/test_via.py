"""The via-cell search (ur3hanoi.plan.motion.via) on synthetic costs: optimum, bounds, infeasibility, purity."""

from __future__ import annotations

import itertools
import math

from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.plan.motion.via import Cell, Pair, best_cells

DIMS: Pair = (5, 4, 6, 3)


def _exact_cost(pair: Pair, a: tuple[float, float], b: tuple[float, float]) -> float:
    return (pair[0] - a[0]) ** 2 + (pair[1] - a[1]) ** 2 + (pair[2] - b[0]) ** 2 + (pair[3] - b[1]) ** 2


@settings(max_examples=40, deadline=None, derandomize=True)
@given(a=st.tuples(st.floats(0, 4), st.floats(0, 3)), b=st.tuples(st.floats(0, 5), st.floats(0, 2)),
       slack=st.floats(0.0, 0.3))
def test_finds_the_minimum_of_a_separable_convex_grid(a: tuple[float, float], b: tuple[float, float],
                                                      slack: float) -> None:
    """Legs (a, b) and motion across 0; the bounds are the exact legs minus ``slack``: the search must still stop
    on the grid's true minimum (a separable convex grid has no other local minimum)."""
    def exact0(c: Cell) -> float:
        return (c[0] - a[0]) ** 2 + (c[1] - a[1]) ** 2

    def exact1(c: Cell) -> float:
        return (c[0] - b[0]) ** 2 + (c[1] - b[1]) ** 2

    best = min(itertools.product(*(range(n) for n in DIMS)), key=lambda p: _exact_cost(p, a, b))  # type: ignore
    got = best_cells(DIMS, (2, 2, 0, 0), (lambda c: exact0(c) - slack, lambda c: exact1(c) - slack),
                     (exact0, exact1), lambda p: 0.0, (0, 0, 0, 0))
    assert _exact_cost(got, a, b) == _exact_cost(best, a, b)


def test_infeasible_legs_are_avoided_and_entry_legs_not_built_for_them() -> None:
    """Exit cells with speed index >= 2 are infeasible (the bound does not know): the search ends on the best
    feasible one, and builds no entry leg while the exit leg it would pair with is infeasible."""
    built: list[tuple[int, Cell]] = []

    def exit_leg(c: Cell) -> float:
        built.append((0, c))
        return math.inf if c[0] >= 2 else 10.0 - c[0]

    def entry_leg(c: Cell) -> float:
        built.append((1, c))
        return 10.0 - c[0]

    got = best_cells((4, 1, 4, 1), (3, 0, 3, 0), (lambda c: 10.0 - c[0], lambda c: 10.0 - c[0]),
                     (exit_leg, entry_leg), lambda p: 0.0, (0, 0, 0, 0))
    assert got == (1, 0, 3, 0)
    assert built[:3] == [(0, (3, 0)), (0, (2, 0)), (0, (1, 0))]  # infeasible exits first, no entry leg between
    assert built[3] == (1, (3, 0)) and len(built) == 4


def test_everything_infeasible_returns_the_fallback() -> None:
    got = best_cells((3, 2, 3, 2), (1, 1, 1, 1), (lambda c: 0.0, lambda c: 0.0), (lambda c: math.inf,) * 2,
                     lambda p: 1.0, (0, 0, 0, 0))
    assert got == (0, 0, 0, 0)


def test_result_is_a_function_of_the_costs_only() -> None:
    """Two searches with the same costs agree whatever was evaluated before (no state between searches)."""
    def bound(c: Cell) -> float:
        return abs(c[0] - 3) + 0.5 * abs(c[1] - 1)

    def exact(c: Cell) -> float:
        return bound(c) + (0.7 if c == (3, 1) else 0.0)

    def across(p: Pair) -> float:
        return 0.1 * abs(p[0] - p[2])

    args = ((6, 3, 6, 3), (0, 0, 5, 2), (bound, bound), (exact, exact), across, (0, 0, 0, 0))
    first = best_cells(*args)  # type: ignore[arg-type]
    best_cells((6, 3, 6, 3), (5, 2, 0, 0), (bound, bound), (exact, exact), across, (0, 0, 0, 0))
    assert best_cells(*args) == first  # type: ignore[arg-type]
