"""What teach says after each record from the third point on: every point's residual and the suspects, so a bad
pose is named the moment it is taught.

Each contact is judged where it can be judged best:

- a point the others check without it (the audit's rule, :func:`ur3hanoi.calibrate.grid_fit.removable`: its tower
  has another point, or the step between levels is fitted) is judged by the calibration's own robust fit
  (:func:`ur3hanoi.calibrate.fit_station`, exactly what ``calibrate`` will say): its residual is its distance from
  the grid fitted to the other points, its suspects are the fit's;
- a point the others cannot check (the only one of its tower: with one point per tower, every point) is judged
  against the base calibration's layout fitted to the other points (:mod:`ur3hanoi.teach.layout`), and named when
  more than the audit's flag distance (:data:`ur3hanoi.audit.rule.CONTACT_FLAG_MM`, 8 mm) off.

Above poses (a hand-edited file may hold them) are judged by the fit only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur3hanoi.audit.rule import CONTACT_FLAG_MM
from ur3hanoi.calibrate import CalibrationFit, fit_station
from ur3hanoi.calibrate.grid_fit import GridSolution, choose_model, leave_one_out, measure, removable, solve
from ur3hanoi.calibrate.taught import TaughtPoints
from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON, contact_point_world
from ur3hanoi.tables.ik_table import pose_label
from ur3hanoi.teach.layout import check_layout

FIRST_FEEDBACK = 3
"""Feedback starts with this many points (one per tower of the lab's three)."""
BY_POINTS = "the other points"
BY_LAYOUT = "the base's layout"


@dataclass(frozen=True)
class PointCheck:
    """One point's line: ``off_mm`` from where the others put it [mm] (NaN: cannot be judged), judged ``by``
    :data:`BY_POINTS` or :data:`BY_LAYOUT` ("" when not judged), ``suspect``."""

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
        layout_turn_deg, layout_shift_mm: how the base's layout sits on the points (turn [deg], shift [mm]).
    """

    rows: tuple[PointCheck, ...]
    suspects: tuple[tuple[int, str], ...]
    fit: CalibrationFit | None
    problem: str
    layout_turn_deg: float
    layout_shift_mm: tuple[float, float, float]

    def lines(self, base_label: str) -> list[str]:
        """The report for the terminal: a table of the points, then one line per suspect (or that all agree)."""
        out = [f"  point  pose               off [mm]  judged against (points over {CONTACT_FLAG_MM:g} mm are named)"]
        for r in self.rows:
            off = "      -" if math.isnan(r.off_mm) else f"{r.off_mm:7.1f}"
            flag = "  SUSPECT" if r.suspect else ""
            by = r.by if r.by != BY_LAYOUT else f"the layout of {printable(base_label)}"
            out.append(f"  {r.index + 1:5d}  {r.label:<17s}  {off}  {by or 'not judged'}{flag}")
        sx, sy, sz = self.layout_shift_mm
        out.append(f"  the towers stand {self.layout_turn_deg:+.1f} deg turned and ({sx:+.1f}, {sy:+.1f}, {sz:+.1f}) "
                   f"mm moved from where {printable(base_label)} puts them")
        out += [why for _, why in self.suspects]
        if self.problem:
            out.append(f"no calibration yet: {self.problem}")
        elif not self.suspects:
            out.append("every point agrees with the others: f finishes, or record the next pose to check more")
        return out


def _free_deviation(base: Station, slots: list[tuple[int, int, int]], p_world: np.ndarray
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Per point: leave-one-out distance [mm] under the calibration's own model, and whether it is checkable."""
    n = len(slots)
    model = choose_model(base, slots)
    if model is None:
        return np.full(n, np.nan), np.zeros(n, dtype=bool)
    can = removable(model, slots)
    sol: GridSolution = solve(base, model, slots, p_world)
    dev, _ = leave_one_out(model, slots, p_world, sol)
    return np.linalg.norm(dev, axis=1) * 1e3, can


def feedback(base: Station, taught: TaughtPoints, base_label: str) -> Feedback:
    """Judge the points of ``taught`` (see the module docstring)."""
    points = taught.points
    slots = [(p.tower, p.height, p.k) for p in points]
    m = measure(base, [p.q for p in points])
    fit: CalibrationFit | None = None
    problem = ""
    try:
        fit = fit_station(base, taught)
        problem = fit.problem
    except TaughtPointsError as exc:
        problem = str(exc).split(": ", 1)[-1]
    free_mm, checkable = _free_deviation(base, slots, m.p_world)
    contacts = [i for i, s in enumerate(slots) if s[2] == ON]
    grid_mm = np.array([contact_point_world(base, points[i].tower, points[i].height) for i in contacts]) * 1e3
    pivot = np.mean(np.asarray(base.tower_origins, dtype=float), axis=0) * 1e3
    layout = check_layout(grid_mm.reshape(-1, 3), m.p_world[contacts].reshape(-1, 3) * 1e3, pivot, CONTACT_FLAG_MM)
    layout_dev = dict(zip(contacts, layout.deviation_mm.tolist(), strict=True))

    suspects: list[tuple[float, int, str]] = []
    fit_suspects = {s.index: s for s in fit.suspects} if fit is not None else {}
    rows = []
    for i, p in enumerate(points):
        label = pose_label(p.tower, p.height, p.k).removesuffix(" on")
        if checkable[i]:
            off, by = float(free_mm[i]), BY_POINTS
            suspect = i in fit_suspects
            if suspect:
                s = fit_suspects[i]
                suspects.append((s.severity, i, f"{label} is suspect: {s.reason}: re-record it?"))
        elif i in layout_dev:
            off, by = layout_dev[i], BY_LAYOUT
            suspect = i in layout.suspects
            if suspect:
                hedge = (" (the points cannot say for sure which one is off: this is the likeliest)"
                         if layout.ambiguous else "")
                suspects.append((off / CONTACT_FLAG_MM, i, f"{label} is {off:.1f} mm from where the other points put "
                                 f"it (with the tower spacing and block size of {printable(base_label)}): re-record "
                                 f"it?{hedge}"))
        else:
            off, by, suspect = math.nan, "", i in fit_suspects
        rows.append(PointCheck(index=i, label=label, off_mm=off, by=by, suspect=suspect))
    suspects.sort(key=lambda s: -s[0])
    shift = tuple(float(x) for x in layout.shift_mm)
    return Feedback(rows=tuple(rows), suspects=tuple((i, why) for _, i, why in suspects), fit=fit, problem=problem,
                    layout_turn_deg=layout.theta_deg, layout_shift_mm=(shift[0], shift[1], shift[2]))


__all__ = ["BY_LAYOUT", "BY_POINTS", "FIRST_FEEDBACK", "Feedback", "PointCheck", "feedback"]
