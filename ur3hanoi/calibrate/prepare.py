"""The taught points a fit starts from: measured by FK, those that cannot take part set aside (each with why), and
the consensus on the rest (:mod:`ur3hanoi.calibrate.consensus`).

A point cannot take part when its slot is outside the base's grid, its joint angles outside the base's limits, or
its tool tilted more than :data:`MAX_TILT_DEG` from pointing down; an "above" pose a table shares between the
heights of a tower is judged apart (:mod:`ur3hanoi.calibrate.fit`). Such points are suspects from the start, never a
reason to stop, unless too little is left to fit the grid (:func:`underdetermined`).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

import numpy as np

from ur3hanoi.calibrate.consensus import Consensus, decide
from ur3hanoi.calibrate.evidence import Evidence
from ur3hanoi.calibrate.grid_fit import BoolArray, Measured, measure
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON
from ur3hanoi.tables import Slot

MAX_TILT_DEG = 10.0  # [deg] a taught pose's tool must point down within this to be used (tables use exactly down)


def fail(source: str, msg: str) -> TaughtPointsError:
    return TaughtPointsError(f"{printable(source)}: {msg}", source=source)


def off_grid(base: Station, p: TaughtPoint) -> bool:
    return not (0 <= p.tower < base.n_towers and 0 <= p.height < base.n_heights)


def hard_problems(base: Station, points: Sequence[TaughtPoint], m: Measured) -> list[str]:
    """Per point, why it cannot take part in the fit ("" if it can)."""
    out = []
    for i, p in enumerate(points):
        if not 0 <= p.tower < base.n_towers:
            out.append(f"tower {p.tower + 1} is outside the base calibration's grid (towers 1..{base.n_towers} in "
                       f"{printable(base.source)})")
        elif not 0 <= p.height < base.n_heights:
            out.append(f"height {p.height + 1} is outside the base calibration's grid (heights 1..{base.n_heights} "
                       f"in {printable(base.source)})")
        elif not base.limits.within_position(np.asarray(p.q, dtype=float)):
            out.append(f"joint angles {np.round(np.degrees(p.q), 3).tolist()} deg are outside the joint limits of "
                       f"{printable(base.source)}")
        elif m.tilt_deg[i] > MAX_TILT_DEG:
            out.append(f"the tool is tilted {m.tilt_deg[i]:.2f} deg from pointing down (more than "
                       f"{MAX_TILT_DEG:g} deg: left out of the fit)")
        else:
            out.append("")
    return out


def underdetermined(where: str, base: Station, points: Sequence[TaughtPoint], candidates: BoolArray,
                     hard: Sequence[str]) -> TaughtPointsError:
    """The "too little left to fit" error: what the grid needs, what is missing, what was left out."""
    usable_on = {p.tower for i, p in enumerate(points) if candidates[i] and p.k == ON}
    lacking = [t + 1 for t in range(base.n_towers) if t not in usable_on]
    need = ("too little left to fit the grid: it needs a usable contact ('on') pose on every tower "
            f"({base.n_towers} towers), and above poses count only on towers that also have one")
    if lacking:
        need += f"; tower(s) {', '.join(map(str, lacking))} have none"
    left_out = [f"{p.label}: {hard[i]}" for i, p in enumerate(points) if hard[i]]
    if left_out:
        more = f" and {len(left_out) - 2} more" if len(left_out) > 2 else ""
        need += f" (left out: {'; '.join(left_out[:2])}{more})"
    if sum("tilted" in h for h in hard) > len(points) // 2:
        need += f"; most poses are tilted: is the tool offset of {printable(base.source)} right?"
    return fail(where, need)


@dataclass(frozen=True)
class Prepared:
    """The points measured, those that cannot take part (``hard``, ``shared``), and the consensus on the rest."""

    m: Measured
    hard: tuple[str, ...]
    shared: BoolArray
    candidates: BoolArray
    off_grid: BoolArray
    safe_slots: list[Slot]
    evidence: Evidence
    consensus: Consensus


def prepare(base: Station, points: Sequence[TaughtPoint], accept: Collection[tuple[int, int]], label: str = ""
             ) -> Prepared:
    m = measure(base, [p.q for p in points])
    hard = tuple(hard_problems(base, points, m))
    shared = np.array([bool(p.shared) and not hard[i] for i, p in enumerate(points)])
    candidates = np.array([not hard[i] and not shared[i] for i in range(len(points))])
    # Points outside the grid take no part; they get placeholder slots (never used) so arrays stay aligned.
    outside = np.array([off_grid(base, p) for p in points])
    safe_slots: list[Slot] = [(0, 0, ON) if outside[i] else (p.tower, p.height, p.k) for i, p in enumerate(points)]
    accepted = np.array([p.k == ON and (p.tower, p.height) in accept for p in points]) & candidates
    ev = Evidence(base=base, slots=tuple(safe_slots), m=m, accepted=accepted, label=label)
    return Prepared(m=m, hard=hard, shared=shared, candidates=candidates, off_grid=outside, safe_slots=safe_slots,
                     evidence=ev, consensus=decide(ev, candidates))


def taught_consensus(base: Station, taught: TaughtPoints | Sequence[TaughtPoint],
                     accept: Collection[tuple[int, int]] = (), base_label: str = "") -> tuple[Consensus, Evidence]:
    """The consensus on taught points (which one is wrong, each point's distance from where the others put it),
    also when they do not determine the grid yet (teach's check after each record); messages name the base
    ``base_label`` (default: its source)."""
    points = taught.points if isinstance(taught, TaughtPoints) else tuple(taught)
    prep = prepare(base, points, accept, base_label)
    return prep.consensus, prep.evidence


__all__ = ["MAX_TILT_DEG", "Prepared", "fail", "hard_problems", "off_grid", "prepare", "taught_consensus",
           "underdetermined"]
