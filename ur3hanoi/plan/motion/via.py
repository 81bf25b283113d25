"""Via states at the "above" points: the search for a connection's best (exit cell, entry cell).

A connection joins the exit leg of the slot it leaves (lift/retreat, ending at the above pose in the via state of
its cell), the joint-space motion across, and the entry leg of the slot it enters (descend, starting at the above
pose in the via state of its cell); its cost is the sum ``exit(c0) + across(c0, c1) + entry(c1)``. The cells of
each slot form a small grid (:class:`~ur3hanoi.plan.motion.legs.SlotLegs`): :func:`best_cells` searches the product.

Each leg has a cheap lower bound (one Ruckig calculation) and an exact duration (the verified leg through interior
points: a small optimisation). The search descends on the costs with the bounds in place of the legs it has not
built yet; where it stops, it builds the legs of that candidate (the exit leg first: an infeasible one makes the
entry leg moot) and descends again with what it learnt, until it stops on a candidate whose legs are both built:
a local minimum of the exact costs among the bounds of its neighbours. Only what the search itself learnt enters
its decisions (never what another connection built), so the result is a function of the connection alone.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

Cell = tuple[int, int]
Pair = tuple[int, int, int, int]  # exit cell, entry cell
# Descents per search: each one after the first follows a leg found infeasible; the lab's connections take at most 4.
MAX_DESCENTS = 8


def _descend(cur: Pair, dims: Sequence[int], cost: Callable[[Pair], float]) -> Pair:
    """Steepest descent over the 8 grid neighbours (first best on ties) from ``cur``."""
    while True:
        best_cost, best = cost(cur), cur
        for d, n in enumerate(dims):
            for step in (-1, 1):
                k = cur[d] + step
                if 0 <= k < n:
                    nb: Pair = (*cur[:d], k, *cur[d + 1:])  # type: ignore[assignment]
                    c = cost(nb)
                    if c < best_cost:
                        best_cost, best = c, nb
        if best == cur:
            return cur
        cur = best


def best_cells(dims: Pair, start: Pair, bounds: tuple[Callable[[Cell], float], Callable[[Cell], float]],
               exacts: tuple[Callable[[Cell], float], Callable[[Cell], float]], across: Callable[[Pair], float],
               fallback: Pair) -> Pair:
    """The (exit cell, entry cell) of least exact cost found by bound-guided descent from ``start``.

    ``dims``: grid sizes (exit speeds, exit accelerations, entry speeds, entry accelerations). ``bounds[k](c) <=
    exacts[k](c)`` for the exit (k = 0) and entry (k = 1) legs; inf marks an infeasible leg or motion across. If the
    descent ends on an infeasible candidate, it restarts from the least-cost candidate seen; after
    :data:`MAX_DESCENTS` descents it takes the best candidate whose legs it built. If nothing feasible is left, the
    result is ``fallback``, which the caller guarantees to be feasible (the rest-to-rest legs).
    """
    known: tuple[dict[Cell, float], dict[Cell, float]] = ({}, {})
    seen: set[Pair] = set()

    def leg(k: int, c: Cell) -> float:
        return known[k][c] if c in known[k] else bounds[k](c)

    def cost(p: Pair) -> float:
        seen.add(p)
        legs = leg(0, (p[0], p[1])) + leg(1, (p[2], p[3]))
        return legs + across(p) if math.isfinite(legs) else math.inf

    cur = start
    for _ in range(MAX_DESCENTS):
        cur = _descend(cur, dims, cost)
        c0, c1 = (cur[0], cur[1]), (cur[2], cur[3])
        if c0 not in known[0]:
            known[0][c0] = exacts[0](c0)
            if math.isfinite(known[0][c0]) and c1 not in known[1]:
                known[1][c1] = exacts[1](c1)
            continue
        if c1 not in known[1] and math.isfinite(known[0][c0]):
            known[1][c1] = exacts[1](c1)
            continue
        if math.isfinite(cost(cur)):
            return cur
        finite = sorted((cost(p), p) for p in sorted(seen) if math.isfinite(cost(p)))
        if not finite:
            return fallback
        cur = finite[0][1]
    # Out of descents (many infeasible legs around): the best candidate whose legs are both built, else the fallback.
    built = sorted((cost(p), p) for p in sorted(seen)
                   if (p[0], p[1]) in known[0] and (p[2], p[3]) in known[1] and math.isfinite(cost(p)))
    return built[0][1] if built else fallback
