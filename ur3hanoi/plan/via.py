"""Via speeds at the "above" points: a slot's candidate vertical legs, and the search for the best (exit, entry) pair.

The robot passes through the above points without stopping, moving along the vertical line at a speed ``sigma``
[m/s] there. A horizontal segment joins the exit leg of the slot it leaves (lift/retreat) and the entry leg of the
slot it enters (descend); its cost is the summed duration of the three. :func:`best_via_pair` searches the grid
of (exit candidate, entry candidate) for the least cost.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass


@dataclass(frozen=True)
class Leg:
    """A vertical leg's duration [s] for one via speed sigma [m/s] (descend and lift are time-reverses)."""

    sigma: float
    duration: float


class LegCandidates:
    """A slot's candidate legs, fastest via speed first.

    ``solve(sigma)`` returns the leg's duration [s], or None if that via speed is infeasible (the candidate is
    dropped). A leg is solved on first use: the search usually needs only the fastest two or three.
    """

    def __init__(self, speeds: Iterable[float], solve: Callable[[float], float | None],
                 solved: Iterable[Leg] = ()) -> None:
        self._speeds = iter(speeds)
        self._solve = solve
        self._legs: list[Leg] = list(solved)

    @classmethod
    def at_rest(cls) -> LegCandidates:
        """The single candidate of home: at rest (sigma 0), no vertical leg (duration 0)."""
        return cls([], lambda _: None, [Leg(0.0, 0.0)])

    def get(self, i: int) -> Leg | None:
        """The i-th feasible candidate (None: fewer than i + 1 exist)."""
        while len(self._legs) <= i:
            sigma = next(self._speeds, None)
            if sigma is None:
                return None
            duration = self._solve(sigma)
            if duration is not None:
                self._legs.append(Leg(sigma, duration))
        return self._legs[i]

    def count(self) -> int:
        """Number of feasible candidates (solves them all)."""
        while self.get(len(self._legs)) is not None:
            pass
        return len(self._legs)


def best_via_pair(exits: LegCandidates, entries: LegCandidates,
                  cost: Callable[[int, int], float]) -> tuple[int, int]:
    """The (exit i, entry j) candidate pair of least ``cost(i, j)`` (inf: infeasible; ``cost`` should memoize).

    Descent over the candidate grid from the fastest pair (0, 0), stepping to the best improving 4-neighbour: the
    summed duration is unimodal over this grid in practice (the optimum has one of the two speeds at its largest
    candidate), and the descent found the same optimum as the full 6 x 6 search on every connection of the lab
    stations (all pairs, N = 1..3) and of a 10-level grid (N = 1..7), with ~1/7 of the Ruckig calls. If the
    descent ends on an infeasible pair (nothing feasible near the fastest pair), every pair is tried.
    """
    cur = (0, 0)
    while True:
        i, j = cur
        nbrs = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                if i + di >= 0 and j + dj >= 0 and exits.get(i + di) is not None and entries.get(j + dj) is not None]
        nxt = min(nbrs, key=lambda ij: cost(*ij), default=cur)
        if not cost(*nxt) < cost(*cur):
            break
        cur = nxt
    if math.isinf(cost(*cur)):
        cur = min(itertools.product(range(exits.count()), range(entries.count())), key=lambda ij: cost(*ij),
                  default=cur)
    return cur
