"""Which taught point is wrong: the one whose removal leaves the others consistent, judged on all the evidence.

A leave-one-out residual cannot say which point is wrong when the wrong one shares its tower with good ones: the
home pose recorded as tower 1 height 2 bends tower 1's step, and then the good height 3 looks 393 mm off. Nor can
the points alone say where a tower taught once stands (only its level and axis). So every hypothesis "point j is
wrong" is tried: the other points are judged on everything the calibration knows that does not depend on where the
towers stand (:func:`ur3hanoi.calibrate.evidence.judge`: positions, the table's levels, the tool's axis, the height
step and block size, the approach, distinct towers, each against the audit's always-flagged limit), and the
hypothesis that leaves them consistent is the answer (:func:`decide`).

The decision: when all the candidates are consistent, no point is grossly wrong (``agree``). Otherwise each
candidate is left out in turn (not the ``accepted`` ones). Among the hypotheses that leave the rest consistent,
the one with the smallest score (the sum of every check's squared share of its limit, plus the headings over
theirs) names the wrong point (``named``) unless another one scores within :data:`AMBIGUOUS_SCORE`: then the points
cannot tell which one is wrong (``undecided``, naming them all). When no single point leaves the rest consistent,
more than one is wrong or the base does not fit the station (``unexplained``): the robust fit
(:mod:`ur3hanoi.calibrate.robust`) takes over.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from ur3hanoi.calibrate.evidence import Evidence, Judgement, judge
from ur3hanoi.calibrate.grid_fit import BoolArray, Measured
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON
from ur3hanoi.tables import Slot

AMBIGUOUS_SCORE = 1.0
"""Another hypothesis scoring within this of the best (one check at its limit) could be the answer as well."""
MAX_HYPOTHESES = 12
"""With more candidates than this, only the points a disagreement involves are left out in turn (this many at
most, the most involved first)."""


@dataclass(frozen=True)
class Consensus:
    """What :func:`decide` found: ``kind`` (``agree``, ``named``, ``undecided``, ``unexplained``), the points
    ``wrong`` (best first), ``alone`` (the named point is its tower's only contact: nothing can be written without
    it), the judgement of all the candidates (``whole``) and of the chosen set (``chosen``: all but the named point;
    all but the best when undecided), and each hypothesis tried."""

    kind: str
    wrong: tuple[int, ...]
    alone: bool
    whole: Judgement
    chosen: Judgement
    tried: dict[int, Judgement] = field(default_factory=dict)


def decide(ev: Evidence, candidates: BoolArray) -> Consensus:
    """Which candidate point is wrong (see the module docstring)."""
    whole = judge(ev, candidates)
    if whole.consistent:
        return Consensus("agree", (), False, whole, whole)
    tried = {j: judge(ev, candidates & (np.arange(len(candidates)) != j)) for j in _suspects(ev, candidates, whole)}
    fits = sorted((h.score, j) for j, h in tried.items() if h.consistent)
    if not fits:  # the station's own scatter may leave a good contact a little past the limit
        fits = sorted((h.score, j) for j, h in tried.items() if _within_scatter(h))
    if not fits:
        return Consensus("unexplained", (), False, whole, whole, tried)
    best_score, best = fits[0]
    rivals = tuple(j for s, j in fits[1:] if s < best_score + AMBIGUOUS_SCORE)
    t = ev.slots[best][0]
    alone = ev.slots[best][2] == ON and not any(
        candidates[i] and i != best and s[0] == t and s[2] == ON for i, s in enumerate(ev.slots))
    if rivals:
        return Consensus("undecided", (best, *rivals), alone, whole, tried[best], tried)
    return Consensus("named", (best,), alone, whole, tried[best], tried)


SCATTER_SHARE = 1.5
"""A hypothesis that leaves only contacts off the grid by at most this share of the always-flagged distance (12 mm)
still names its point when no hypothesis leaves the rest fully consistent: real stations' contacts scatter up to
about 10 mm off the grid the others fit (the audit's robust fit calls such tables clean)."""


def _within_scatter(j: Judgement) -> bool:
    over = [c for c in j.checks if c.over and not c.soft]
    return all(c.what == "point" and c.share <= SCATTER_SHARE for c in over)


def _suspects(ev: Evidence, candidates: BoolArray, whole: Judgement) -> list[int]:
    """The candidates to leave out in turn: all of them, or with more than :data:`MAX_HYPOTHESES` the ones a
    disagreement involves (the points judged, every contact of a tower judged, the step's towers), worst first."""
    cand = [int(i) for i in np.flatnonzero(candidates & ~ev.accepted)]
    if len(cand) <= MAX_HYPOTHESES:
        return cand
    share: dict[int, float] = {}
    for c in whole.checks:
        if not c.over or c.soft:
            continue
        if c.what in ("level", "lean"):
            involved = [i for i in cand if ev.slots[i][0] == c.index]
        elif c.what == "distinct":
            involved = [i for i in cand if ev.slots[i][0] in (c.index, c.other)]
        elif c.what == "step":
            involved = [i for i in cand if ev.slots[i][2] == ON]
        else:
            involved = [c.index]
        for i in involved:
            share[i] = max(share.get(i, 0.0), c.share)
    return sorted((i for i in share if i in cand), key=lambda i: -share[i])[:MAX_HYPOTHESES]


def consensus(base: Station, slots: Sequence[Slot], m: Measured, candidates: BoolArray,
              accepted: BoolArray | None = None) -> Consensus:
    """:func:`decide` for the points measured at ``slots`` (``m``) of which ``candidates`` may take part;
    ``accepted`` points are never left out and their towers never judged by their level or axis."""
    ok = np.zeros(len(slots), dtype=bool) if accepted is None else np.asarray(accepted, dtype=bool)
    return decide(Evidence(base=base, slots=tuple(slots), m=m, accepted=ok & candidates), candidates)


__all__ = ["AMBIGUOUS_SCORE", "MAX_HYPOTHESES", "SCATTER_SHARE", "Consensus", "consensus", "decide"]
