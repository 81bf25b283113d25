"""What teach says after each record from the third point on: every point's distance from where the others put it,
and the point that is wrong, so a bad pose is named the moment it is taught.

The judgement is the calibration's own (:func:`ur3hanoi.calibrate.prepare.taught_consensus`, what ``calibrate``
and ``f`` decide): a point that shares its tower with another is judged by the other points, a tower taught once
by its level against the other towers' (nothing checks where it stands along the table: the feedback says so),
each against the audit's always-flagged distance (:data:`ur3hanoi.calibrate.limits.CONTACT_FLAG_MM`, 8 mm);
which point is wrong is the one whose removal leaves the others consistent (:mod:`ur3hanoi.calibrate.consensus`),
named with what probably happened (the arm at home, the wrong slot, a typo in one joint, not on the block). It works
before every tower is taught too. The robust fit's finer suspects (over its own thresholds of a few mm) are named
after it.
"""

from __future__ import annotations

import math
from collections.abc import Collection
from dataclasses import dataclass, replace

from ur3hanoi.calibrate import CalibrationFit, fit_station
from ur3hanoi.calibrate.evidence import BY_LEVEL as LEVEL
from ur3hanoi.calibrate.evidence import BY_POINTS as POINTS
from ur3hanoi.calibrate.limits import CONTACT_FLAG_MM
from ur3hanoi.calibrate.prepare import taught_consensus
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.calibrate.verdict import named_text, refusal, where_text
from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import pose_label

FIRST_FEEDBACK = 3
"""Feedback starts with this many points (one per tower of the lab's three)."""
BY_POINTS = "the other points"
BY_LEVEL = "the other towers' level (not sideways)"
BY_LAYOUT = BY_LEVEL  # issue 33's name: a tower taught once is judged by its level now (issue 37)


@dataclass(frozen=True)
class PointCheck:
    """One point's line: ``off_mm`` from where the others put it [mm] (NaN: cannot be judged), judged ``by``
    :data:`BY_POINTS` or :data:`BY_LEVEL` ("" when not judged), ``suspect``."""

    index: int
    label: str
    off_mm: float
    by: str
    suspect: bool


@dataclass(frozen=True)
class Feedback:
    """The verdict on the points taught so far.

    Attributes:
        rows: one per point, in file order.
        suspects: (point index, what to say), worst first.
        fit: the calibration's fit (None when the points do not determine the grid yet).
        problem: why there is no fit yet, or why it is not sound ("" when it is).
        layout_turn_deg, layout_shift_mm: how the base's layout sits on the points (turn [deg], shift [mm]; for
            people: real towers stand anywhere).
        single: the towers (0-based) resting on one pose: nothing checks them sideways.
    """

    rows: tuple[PointCheck, ...]
    suspects: tuple[tuple[int, str], ...]
    fit: CalibrationFit | None
    problem: str
    layout_turn_deg: float
    layout_shift_mm: tuple[float, float, float]
    single: tuple[int, ...] = ()

    def lines(self, base_label: str) -> list[str]:
        """The report for the terminal: a table of the points, then one line per suspect (or that all agree)."""
        out = [f"  point  pose               off [mm]  judged against (points over {CONTACT_FLAG_MM:g} mm are named)"]
        for r in self.rows:
            off = "      -" if math.isnan(r.off_mm) else f"{r.off_mm:7.1f}"
            flag = "  SUSPECT" if r.suspect else ""
            by = r.by
            out.append(f"  {r.index + 1:5d}  {r.label:<17s}  {off}  {by or 'not judged'}{flag}")
        sx, sy, sz = self.layout_shift_mm
        out.append(f"  the towers stand {self.layout_turn_deg:+.1f} deg turned and ({sx:+.1f}, {sy:+.1f}, {sz:+.1f}) "
                   f"mm moved from where {printable(base_label)} puts them")
        out += [why for _, why in self.suspects]
        if self.problem:
            out.append(f"no calibration yet: {self.problem}")
        elif not self.suspects and self.single:
            out.append(f"every point agrees with the others; {_towers_text(self.single)} on one pose: nothing checks "
                       "where it stands along the table (a joint-1 offset would move it unseen). The next pose checks "
                       "it; f writes now, with that note")
        elif not self.suspects:
            out.append("every point agrees with the others: f finishes, or record the next pose to check more")
        return out


def _line(reason: str) -> str:
    """A suspect's reason, saying what to do once."""
    return reason if reason.rstrip("?").endswith("re-record it") else f"{reason}: re-record it?"


def feedback(base: Station, taught: TaughtPoints, base_label: str, accept: Collection[tuple[int, int]] = ()
             ) -> Feedback:
    """Judge the points of ``taught`` (see the module docstring); ``accept``: the ``(tower, height)`` slots
    (0-based) taken on the student's word."""
    points = taught.points
    c, ev = taught_consensus(base, taught, accept, base_label)
    fit: CalibrationFit | None = None
    problem = ""
    try:
        fit = fit_station(base, taught, accept=accept)
        problem = fit.problem
    except TaughtPointsError as exc:
        problem = str(exc).split(": ", 1)[-1]
    if fit is not None and fit.consensus == "agree" and c.kind in ("undecided", "unexplained"):
        c = replace(c, kind="agree", wrong=(), alone=False, chosen=c.whole)  # the station's scatter, as f judges it
    judged = c.chosen
    suspects: list[tuple[int, str]] = []
    if c.kind == "named":
        i = c.wrong[0]
        suspects.append((i, f"{_label(points[i])} is {where_text(ev, c, i)}; {named_text(ev, c, i, points)}"))
    elif c.kind == "undecided":
        suspects.append((c.wrong[0], refusal(ev, c, points)))
    if c.kind == "undecided" or (c.kind == "named" and c.alone):
        problem = ""  # the line above says why, and what to do
    elif fit is not None:  # the fit's finer suspects, among the points the others check
        suspects += [(s.index, f"{_label(points[s.index])} is suspect: {_line(s.reason)}") for s in fit.suspects
                     if s.index not in c.wrong and judged.by[s.index] != LEVEL]
    rows = []
    flagged = {i for i, _ in suspects} | set(c.wrong)
    for i, p in enumerate(points):
        by = judged.by[i]
        rows.append(PointCheck(index=i, label=_label(p), off_mm=float(judged.off_mm[i]),
                               by=BY_POINTS if by == POINTS else BY_LEVEL if by == LEVEL else "",
                               suspect=i in flagged))
    layout = judged.layout
    turn = math.degrees(layout.theta) if layout is not None else 0.0
    sx, sy, sz = (float(v) for v in layout.shift) if layout is not None else (0.0, 0.0, 0.0)
    single = tuple(t for t, _, _ in fit.single_pose) if fit is not None else ()
    return Feedback(rows=tuple(rows), suspects=tuple(suspects), fit=fit, problem=problem, layout_turn_deg=turn,
                    layout_shift_mm=(sx, sy, sz), single=single)


def finish_problem(base: Station, taught: TaughtPoints, accept: Collection[tuple[int, int]] = ()) -> str:
    """Why the calibration cannot be written from the points taught ("" when it can): what ``f`` checks first."""
    try:
        return fit_station(base, taught, accept=accept).problem
    except TaughtPointsError as exc:
        return str(exc).split(": ", 1)[-1]


def _towers_text(towers: tuple[int, ...]) -> str:
    """``tower 2 rests`` / ``towers 1, 2 and 3 rest``."""
    if len(towers) == 1:
        return f"tower {towers[0] + 1} rests"
    names = [str(t + 1) for t in towers]
    return f"towers {', '.join(names[:-1])} and {names[-1]} rest"


def _label(p: TaughtPoint) -> str:
    return pose_label(p.tower, p.height, p.k).removesuffix(" on")


__all__ = ["BY_LAYOUT", "BY_LEVEL", "BY_POINTS", "FIRST_FEEDBACK", "Feedback", "PointCheck", "feedback",
           "finish_problem"]
