"""Judge a set of taught points on all the evidence a calibration has that does not depend on where the towers
stand: where the points are, the table's levels, the tool's axis, the height step and block size, the approach,
distinct towers (:func:`judge`; :mod:`ur3hanoi.calibrate.consensus` tries the sets without each point in turn).

The base calibration gives the robot, the tool, the block size and the approach, not where the towers stand: real
stations' towers stand 12-105 mm from where its layout, moved and turned as a whole, puts them (issue 37). The
evidence, each with the audit's always-flagged limit (:mod:`ur3hanoi.calibrate.limits`); a set of points is
consistent when nothing is over its limit:

- **positions**: a contact that the others check (its tower has another contact, or the step is fitted without it)
  is within :data:`CONTACT_FLAG_MM` (8 mm) of where the grid fitted to the other points puts it (an above pose:
  its horizontal place, within :data:`ABOVE_FLAG_LINE_MM`, 10 mm: its height is the approach's);
- **the height step and the block size**: when one tower alone fixes the step, the top level it gives is within
  8 mm of where the base's step (one block up; a flat base: its row step turned with the towers) puts it;
- **the table's levels, the tool's axis, distinct towers** (:mod:`ur3hanoi.calibrate.table_checks`): every
  tower's origin at the other towers' height within 8 mm; a contact's suction axis within :data:`TILT_FLAG_DEG`
  (5 deg) of its tower's other contacts', a tower's within 8 deg of the other towers'; towers a block apart. A
  tower the student vouched for (``accepted``) is not judged by these;
- **the tool's heading** (the direction the arm came from) is weighed, never alone a reason (a round cup does not
  care, and freedrive turns it): a heading more than ``max(HEADING_DEG, 5 x the others' spread)`` from the others'
  counts against the point when hypotheses compete;
- **the approach**: an above pose stands within :data:`ABOVE_FLAG_LINE_MM` (10 mm) of its tower's vertical line,
  at least :data:`ABOVE_MIN_MM` (5 mm) and at most :data:`MAX_APPROACH_M` over its contact, and as high over it as
  the other above poses (the calibration has one approach height): within ``max(8 mm, 5 x their spread)``.

A tower taught at one contact is judged by its level and axis only: nothing checks where it stands along the table
(a joint-1 offset moves it with nothing else changed); the calibration says so
(:attr:`ur3hanoi.calibrate.result.CalibrationFit.single_pose`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.grid_fit import FLAT_STEP_PASSES, BoolArray, Measured, default_height_step
from ur3hanoi.calibrate.layout import LayoutFit, fit_layout
from ur3hanoi.calibrate.limits import (
    ABOVE_FLAG_LINE_MM,
    ABOVE_MIN_MM,
    CONTACT_FLAG_MM,
    MAX_APPROACH_M,
    TILT_FLAG_DEG,
)
from ur3hanoi.calibrate.table_checks import TOWER_TILT_DEG, distinct_checks, level_checks, share, tilt_checks
from ur3hanoi.errors import printable
from ur3hanoi.robot.ik import wrap_angle
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON
from ur3hanoi.tables import Slot

HEADING_DEG = 15.0
"""[deg] a heading this far from the others' (or 5 times their spread) weighs against a point."""
UNJUDGED_SCORE = 2.0
"""What an above pose left with nothing to judge it adds to a hypothesis' score (two checks at their limit): with
its tower's only contact left out, it would agree with anything."""
SPREAD_SIGMAS = 5.0
"""Headings and approach heights: a point past this many times the others' spread (their median deviation) disagrees
when that is more than the limit (the data's own scatter sets the bar where hand-recorded tables scatter widely)."""
BY_POINTS, BY_LEVEL = "points", "level"
BY_LAYOUT = BY_LEVEL  # the name issue 33 used; a tower taught once is judged by its level now


@dataclass(frozen=True)
class Check:
    """One piece of evidence about a set of points: ``what`` it is about (``point``, ``tilt``, ``above``, ``over``,
    ``approach``, ``step``, ``layout``, ``heading``), the point (or, for ``layout``, the tower; -1 for ``step``) it
    judges, its ``value`` [mm or deg] and its ``share`` of the limit (over 1: disagrees); ``soft`` checks are weighed
    only."""

    what: str
    index: int
    value: float
    share: float
    soft: bool = False
    other: int = -1

    @property
    def over(self) -> bool:
        return self.share > 1.0


@dataclass(frozen=True)
class Judgement:
    """A set of points (``kept``) judged on all the evidence.

    Attributes:
        kept: shape (N,), the points judged.
        checks: every check made.
        origins_m: (T, 3) [m, world] the tower origins the kept contacts give (NaN rows: no kept contact).
        step_m: (3,) [m, world] their height step; step_fitted: whether they fix it.
        expected_m: (N, 3) [m, world] where the kept points put each point's slot (NaN where they cannot say).
        off_mm: (N,) each point's distance [mm] from where the others put it: for a kept point the check that
            judged it (NaN when none could), for one left out its distance from ``expected_m``.
        by: per point, :data:`BY_POINTS` (the other points placed it) or :data:`BY_LEVEL` (its tower's only
            contact: only its height is judged, by the other towers' level), or "".
        layout: the base's layout fitted to the kept towers (None with none): a hint, never evidence.
        level_m: (H,) [m, world] each height's level where the kept towers put it (NaN with none).
        unjudged: how many kept above poses stand over a tower with no kept contact (nothing judges them).
    """

    kept: BoolArray
    checks: tuple[Check, ...]
    origins_m: FloatArray
    step_m: FloatArray
    step_fitted: bool
    expected_m: FloatArray
    off_mm: FloatArray
    by: tuple[str, ...]
    layout: LayoutFit | None
    level_m: FloatArray = field(default_factory=lambda: np.zeros(0))
    unjudged: int = 0

    @property
    def consistent(self) -> bool:
        return not any(c.over and not c.soft for c in self.checks)

    @property
    def score(self) -> float:
        """The checks' squared shares of their limits, plus :data:`UNJUDGED_SCORE` for each kept above pose over a
        tower with no kept contact: a hypothesis that leaves a point nothing can judge explains less."""
        return float(sum(c.share**2 for c in self.checks if not c.soft or c.over)) + UNJUDGED_SCORE * self.unjudged


@dataclass(frozen=True)
class Evidence:
    """What the checks read: the base, each point's slot and FK (``m``), the points the student vouched for, and how
    messages name the base (``label``; default its source)."""

    base: Station
    slots: tuple[Slot, ...]
    m: Measured
    accepted: BoolArray
    label: str = ""

    @property
    def base_label(self) -> str:
        return printable(self.label or self.base.source)

    @property
    def base_origins_mm(self) -> FloatArray:
        return np.asarray(self.base.tower_origins, dtype=float) * 1e3


def _prior_step(base: Station, origins: FloatArray) -> FloatArray:
    """The step the base expects [m]: one block up (stacked), its row step turned with the towers present (flat:
    by the turn of the base's layout fitted to them)."""
    present = ~np.isnan(origins[:, 0])
    step = default_height_step(base, None)
    if base.layout != "flat" or present.sum() < 2:
        return step
    base_mm = np.asarray(base.tower_origins, dtype=float) * 1e3
    fit = fit_layout(base_mm[present], origins[present] * 1e3, base_mm.mean(axis=0))
    c, s = math.cos(fit.theta), math.sin(fit.theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ step


def _design(ev: Evidence, rows: list[tuple[int, int]], axes: tuple[int, ...], approach: bool) -> FloatArray:
    """Least-squares rows (point, axis): columns the towers' origins, the step's ``axes``, then the approach."""
    n_t = ev.base.n_towers
    A = np.zeros((len(rows), 3 * n_t + len(axes) + int(approach)))
    for r, (i, a) in enumerate(rows):
        t, h, k = ev.slots[i]
        A[r, 3 * t + a] = 1.0
        if a in axes:
            A[r, 3 * n_t + axes.index(a)] = h
        if approach and k == ABOVE and a == 2:
            A[r, -1] = 1.0
    return A


def _model(ev: Evidence, idx: list[int], n_present: int
           ) -> tuple[list[tuple[int, int]], FloatArray, tuple[int, ...], list[int]]:
    """The rows, design and fitted step axes of the kept points ``idx``, and the points that fix the step.

    Contacts count in x, y and z, above poses in x and y (their height is the approach's), unless nothing else
    fixes a stacked step: then their heights do, with a shared approach (as in the calibration's own fit). A step
    the points do not fix is the base's (no axes)."""
    above = [i for i in idx if ev.slots[i][2] == ABOVE]
    rows = [(i, a) for i in idx for a in ((0, 1, 2) if ev.slots[i][2] == ON else (0, 1))]
    axes = (0, 1) if ev.base.layout == "flat" else (0, 1, 2)
    A = _design(ev, rows, axes, False)
    if rows and int(np.linalg.matrix_rank(A)) == 3 * n_present + len(axes):
        fixing = [i for i in idx if ev.slots[i][2] == ON or ev.base.layout == "flat"]
        return rows, A, axes, fixing
    if above and ev.base.layout != "flat":
        rows_z = rows + [(i, 2) for i in above]
        A = _design(ev, rows_z, axes, True)
        if int(np.linalg.matrix_rank(A)) == 3 * n_present + len(axes) + 1:
            return rows_z, A, axes, idx
    return rows, _design(ev, rows, (), False), (), []


def _grid(ev: Evidence, kept: np.ndarray) -> tuple[FloatArray, FloatArray, bool, FloatArray, BoolArray, int]:
    """The grid of the kept points (contacts, and the horizontal place of above poses over a tower with a contact),
    by least squares (:func:`_model`): (origins (T, 3) [m] NaN where no contact, step, fitted?, each point's
    deviation (N, 3) from the grid of the others [m] (NaN where they cannot say), checkable (N,), the number of
    towers whose points fix the step)."""
    base, n_t, n = ev.base, ev.base.n_towers, len(ev.slots)
    idx = [int(i) for i in kept]
    present = np.zeros(n_t, dtype=bool)
    for i in idx:
        present[ev.slots[i][0]] |= ev.slots[i][2] == ON
    idx = [i for i in idx if present[ev.slots[i][0]]]
    rows, A, axes, fixing = _model(ev, idx, int(present.sum()))
    fitted = bool(axes)
    p = np.array([ev.m.p_world[i, a] for i, a in rows])
    h_rows = np.array([ev.slots[i][1] for i, _ in rows], dtype=float)
    a_rows = np.array([a for _, a in rows], dtype=int)
    step, origins, x = default_height_step(base, None), np.full((n_t, 3), np.nan), np.zeros(A.shape[1])
    for _ in range(1 if fitted else FLAT_STEP_PASSES):  # an unfitted flat step turns with the towers it places
        if rows:
            x = np.linalg.lstsq(A, p - (0.0 if fitted else h_rows * step[a_rows]), rcond=None)[0]
            origins = np.where(present[:, None], x[:3 * n_t].reshape(n_t, 3), np.nan)
        if fitted:
            step = np.zeros(3)
            step[list(axes)] = x[3 * n_t:3 * n_t + len(axes)]
        else:
            new = _prior_step(base, origins)
            settled = bool(np.max(np.abs(new - step)) < 1e-13)
            step = new
            if settled:
                break
    dev, can = np.full((n, 3), np.nan), np.zeros(n, dtype=bool)
    if rows:
        residual = p - A @ x - (0.0 if fitted else h_rows * step[a_rows])
        inv = np.linalg.pinv(A.T @ A)
        of: dict[int, list[int]] = {}
        for k, (j, _) in enumerate(rows):
            of.setdefault(j, []).append(k)
        for i in idx:
            r = of[i]
            M = np.eye(len(r)) - A[r] @ inv @ A[r].T
            if float(np.min(np.linalg.eigvalsh(0.5 * (M + M.T)))) > 1e-9:
                dev[i, a_rows[r]] = np.linalg.solve(M, residual[r])
                can[i] = True
    stepped = sum(len({ev.slots[i][1] for i in fixing if ev.slots[i][0] == t}) > 1 for t in range(n_t))
    return origins, step, fitted, dev, can, stepped


def _headings(ev: Evidence, kept: np.ndarray) -> list[Check]:
    """Each kept point's heading against the circular mean of the others' (soft checks)."""
    n = len(kept)
    if n < 3:
        return []
    h = ev.m.heading[kept]
    sin, cos = np.sin(h), np.cos(h)
    mean = np.arctan2(sin.sum() - sin, cos.sum() - cos)  # of the others, per point
    dev = np.abs(np.degrees(wrap_angle(h[None, :] - mean[:, None])))  # row j: every heading from j's others' mean
    off = dev[np.arange(n), np.arange(n)]
    spread = np.median(dev[~np.eye(n, dtype=bool)].reshape(n, n - 1), axis=1)
    limit = np.maximum(HEADING_DEG, SPREAD_SIGMAS * spread)
    return [Check("heading", int(i), float(o), float(o / lim), soft=True) for i, o, lim in zip(kept, off, limit,
                                                                                                  strict=True)]


def _layout(ev: Evidence, origins: FloatArray) -> LayoutFit | None:
    """The base's layout moved and turned onto the towers the points place (how far they stand from it, for people:
    never evidence, real towers stand anywhere); None with none."""
    base_mm = ev.base_origins_mm
    present = [t for t in range(len(origins)) if not np.isnan(origins[t, 0])]
    return fit_layout(base_mm[present], origins[present] * 1e3, base_mm.mean(axis=0)) if present else None


def _table_checks(ev: Evidence, origins: FloatArray, contact: np.ndarray, accepted_towers: set[int]) -> list[Check]:
    """The layout-independent evidence (:mod:`ur3hanoi.calibrate.table_checks`): levels, the tool's axis, distinct
    towers."""
    towers = [ev.slots[i][0] for i in contact]
    judged = [t for t in sorted(set(towers)) if t not in accepted_towers]
    checks = [Check("level", t, dz, share(dz, CONTACT_FLAG_MM)) for t, dz in level_checks(origins, judged)]
    per_point, lean = tilt_checks(ev.m.R_world[contact, :, 2], towers)
    checks += [Check("tilt", int(contact[j]), a, a / TILT_FLAG_DEG) for j, a in per_point]
    checks += [Check("lean", t, a, a / TOWER_TILT_DEG) for t, a in lean if t not in accepted_towers]
    block_mm = ev.base.block_size * 1e3
    checks += [Check("distinct", a, d, block_mm / max(d, 1e-6), other=b)
               for a, b, d in distinct_checks(origins, ev.base.block_size)
               if not (a in accepted_towers and b in accepted_towers)]
    return checks


def judge(ev: Evidence, kept: BoolArray) -> Judgement:
    """Judge the points ``kept`` on all the evidence (see the module docstring)."""
    n = len(ev.slots)
    is_on = np.array([s[2] == ON for s in ev.slots], dtype=bool)
    contact = np.flatnonzero(kept & is_on)
    origins, step, step_fitted, dev, can, n_stepped = _grid(ev, np.flatnonzero(kept))
    checks: list[Check] = []
    off, by = np.full(n, np.nan), [""] * n
    for i in np.flatnonzero(can):  # an above pose by its horizontal place only (its height is the approach's)
        d = float(np.linalg.norm(np.nan_to_num(dev[i] if is_on[i] else dev[i, :2]))) * 1e3
        limit = CONTACT_FLAG_MM if is_on[i] else ABOVE_FLAG_LINE_MM
        checks.append(Check("point" if is_on[i] else "above", int(i), d, d / limit))
        off[i], by[i] = d, BY_POINTS
    prior = _prior_step(ev.base, origins)
    for i in contact[~can[contact]]:  # shown against the tower's other contacts a block (the base's step) apart
        t, h, _ = ev.slots[i]
        mates = [k for k in contact if k != i and ev.slots[k][0] == t]
        if mates:
            there = np.mean([ev.m.p_world[k] + (h - ev.slots[k][1]) * prior for k in mates], axis=0)
            off[i], by[i] = float(np.linalg.norm(ev.m.p_world[i] - there)) * 1e3, BY_POINTS
    if n_stepped == 1:  # one tower alone fixes the step: only the base's block size can check it
        top = (ev.base.n_heights - 1) * float(np.linalg.norm(step - prior)) * 1e3
        checks.append(Check("step", -1, top, top / CONTACT_FLAG_MM))
    towers = [ev.slots[i][0] for i in contact]
    single = {t: int(contact[j]) for j, t in enumerate(towers) if towers.count(t) == 1}
    accepted_towers = {ev.slots[i][0] for i in contact if ev.accepted[i]}
    layout = _layout(ev, origins)
    table = _table_checks(ev, origins, contact, accepted_towers)
    checks += table
    for c in table:  # a tower taught once: judged by its level alone (nothing checks it sideways)
        if c.what == "level" and c.index in single:
            off[single[c.index]], by[single[c.index]] = abs(c.value), BY_LEVEL
    expected, under = _expected(ev, origins, step, kept)
    present = ~np.isnan(origins[:, 0])
    z0 = float(np.median(origins[present, 2])) if present.any() else np.nan
    level = np.array([z0 + h * step[2] for h in range(ev.base.n_heights)])  # [m] each height's level on the table
    for i in np.flatnonzero(kept & ~is_on):
        checks += _above_checks(ev, int(i), under[i], bool(can[i]))
    checks += _approach_checks(ev, [int(i) for i in np.flatnonzero(kept & ~is_on) if not np.isnan(under[i, 0])],
                               under)
    checks += _headings(ev, np.flatnonzero(kept))
    for i in np.flatnonzero(~kept):
        t, h, _ = ev.slots[i]
        if not np.isnan(origins[t, 0]):
            off[i], by[i] = float(np.linalg.norm(ev.m.p_world[i] - expected[i])) * 1e3, BY_POINTS
        elif is_on[i] and not np.isnan(level[h]):  # its tower's only contact: only the level can say
            off[i], by[i] = abs(float(ev.m.p_world[i, 2] - level[h])) * 1e3, BY_LEVEL
    return Judgement(kept=kept.copy(), checks=tuple(checks), origins_m=origins, step_m=step, step_fitted=step_fitted,
                     expected_m=expected, off_mm=off, by=tuple(by), layout=layout, level_m=level,
                     unjudged=int(sum(np.isnan(under[i, 0]) for i in np.flatnonzero(kept & ~is_on))))


def _expected(ev: Evidence, origins: FloatArray, step: FloatArray, kept: BoolArray) -> tuple[FloatArray, FloatArray]:
    """Where the kept points put each point's slot [m]: the tower's origin (the layout's place for a tower with no
    kept contact) plus its height's steps, an above pose at the kept above poses' approach (else the base's); and
    the contact point under each slot."""
    contact = np.full((len(ev.slots), 3), np.nan)
    for i, (t, h, _) in enumerate(ev.slots):
        if not 0 <= t < ev.base.n_towers:
            continue
        if not np.isnan(origins[t, 0]):  # a tower with no kept contact stands anywhere: nothing to expect
            contact[i] = origins[t] + h * step
    above = [i for i in np.flatnonzero(kept) if ev.slots[i][2] == ABOVE and not np.isnan(contact[i, 0])]
    over = [float(ev.m.p_world[i][2] - contact[i][2]) for i in above]
    approach = float(np.median(over)) if over else ev.base.approach
    expected = contact.copy()
    expected[[s[2] == ABOVE for s in ev.slots], 2] += approach
    return expected, contact


def _above_checks(ev: Evidence, i: int, contact: FloatArray, checked: bool) -> list[Check]:
    """An above pose over its tower's vertical line (unless the others placed it already), over its contact and no
    higher than an approach may be."""
    if np.isnan(contact[0]):
        return []
    d = (ev.m.p_world[i] - contact) * 1e3
    line, over = float(np.hypot(d[0], d[1])), float(d[2])
    height = (1.0 + (ABOVE_MIN_MM - over) / ABOVE_MIN_MM if over < ABOVE_MIN_MM else
              max(ABOVE_MIN_MM / over, over / (MAX_APPROACH_M * 1e3)))
    out = [] if checked else [Check("above", i, line, line / ABOVE_FLAG_LINE_MM)]
    return [*out, Check("over", i, over, height)]


def _approach_checks(ev: Evidence, above: list[int], under: FloatArray) -> list[Check]:
    """The above poses share one approach: each one's height over its contact against the others' median, over
    ``max(8 mm, 5 x the others' spread)`` (hand-recorded tables put them anywhere over the stacks: their spread is
    large, and so is the limit)."""
    over = np.array([ev.m.p_world[i, 2] - under[i, 2] for i in above]) * 1e3
    out = []
    for j, i in enumerate(above):
        others = np.delete(over, j)
        if len(others):
            mid = float(np.median(others))
            spread = float(np.median(np.abs(others - mid)))
            d = abs(float(over[j]) - mid)
            out.append(Check("approach", i, d, d / max(CONTACT_FLAG_MM, SPREAD_SIGMAS * spread)))
    return out


__all__ = ["BY_LAYOUT", "BY_LEVEL", "BY_POINTS", "HEADING_DEG", "SPREAD_SIGMAS", "UNJUDGED_SCORE", "Check",
           "Evidence", "Judgement", "judge"]
