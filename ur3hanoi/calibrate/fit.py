"""Fit a station's grid to taught poses, robustly, and say which poses are suspect and why.

:func:`fit_station` measures every pose by FK with the base calibration's robot base and tool
(:mod:`~ur3hanoi.calibrate.grid_fit`), decides which point (if any) is grossly wrong on all the evidence
(:mod:`~ur3hanoi.calibrate.consensus`), fits the grid with sequential leave-one-out deletion
(:mod:`~ur3hanoi.calibrate.robust`), and explains each suspect (:mod:`~ur3hanoi.calibrate.verdict` for the point
the consensus named, :mod:`~ur3hanoi.calibrate.explain` for the others).

The point the consensus names is left out of the fit (when the robust fit would have kept it, the fit is made
again without it). When it is its tower's only contact nothing can be written without it, and when the points
cannot tell which of several is wrong nothing can be written either: the fit is returned with
:attr:`CalibrationFit.problem` saying which and what to do. A tower taught once stands where the base's layout,
moved and turned onto the other towers, puts it (within the always-flagged 8 mm) unless the student accepts its
point (``accept``). When no single point explains a disagreement, the robust fit's choice is judged the same way
and refused if it still disagrees.

Points that cannot take part in the fit are suspects from the start, never a reason to stop: a slot outside the
base's grid, joint angles outside its limits, a tool tilted more than :data:`MAX_TILT_DEG` from pointing down. An
"above" pose a table shares between the heights of a tower is not a grid point of any one height: it is checked
to stand over the tower (its horizontal distance from the vertical through each contact point it serves) and at
least one block above each of those contact points, and does not enter the fit.

The fit fails (:class:`~ur3hanoi.errors.TaughtPointsError`) only when the remaining points do not determine the
grid: at least one usable contact ("on") pose on every tower is needed, and above poses only count on towers that
also have a contact pose. A fit whose result is doubtful is returned with :attr:`CalibrationFit.problem` set
(:attr:`CalibrationFit.sound` False): more than half the points disagree with the grid, a point that cannot be left
out is off, or the fitted grid itself is invalid. :func:`~ur3hanoi.calibrate.write_calibration` refuses to write
it.
"""

from __future__ import annotations

import math
from collections.abc import Collection, Sequence
from dataclasses import dataclass, replace

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.consensus import SCATTER_SHARE, Consensus
from ur3hanoi.calibrate.evidence import judge
from ur3hanoi.calibrate.explain import diagnose
from ur3hanoi.calibrate.grid_fit import (
    BoolArray,
    GridModel,
    GridSolution,
    Measured,
    choose_model,
)
from ur3hanoi.calibrate.limits import ABOVE_FLAG_LINE_MM, CONTACT_FLAG_MM, MAX_APPROACH_M
from ur3hanoi.calibrate.prepare import MAX_TILT_DEG, Prepared, fail, prepare, underdetermined
from ur3hanoi.calibrate.result import CalibrationFit, Suspect
from ur3hanoi.calibrate.robust import RobustFit, robust_fit
from ur3hanoi.calibrate.table_checks import single_pose_towers
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.calibrate.verdict import named_text, refusal, slot_text, unexplained, where_text
from ur3hanoi.errors import CalibrationError, printable
from ur3hanoi.robot.ik import wrap_angle
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON
from ur3hanoi.tables import Slot

# ------------------------------------------------------------------------------------------------- fitting


def _station(base: Station, model: GridModel, solution: GridSolution, yaw: float, source: str
             ) -> tuple[Station, str]:
    """The fitted station, and the problem that makes it invalid ("" if none)."""
    # Rounded to 1e-12 m (far below any physical meaning) so exact fits write 0.0 rather than -0.0 or 1e-17.
    origins = np.round(solution.origins, 12) + 0.0
    step = np.round(solution.step, 12) + 0.0
    approach = round(solution.approach, 12) if model.fit_approach else base.approach
    unvalidated = replace(base, tower_origins=tuple((float(x), float(y), float(z)) for x, y, z in origins),
                          height_step=(float(step[0]), float(step[1]), float(step[2])), tool_yaw=float(yaw),
                          approach=float(approach), source=source, sha256="")
    if not 0.0 < approach <= MAX_APPROACH_M:
        return unvalidated, (f"the fitted approach height {approach:.4f} m is outside (0, {MAX_APPROACH_M:g}] m: are "
                             "some contact poses marked 'above' (or the reverse)?")
    try:
        return base.with_grid(origins, step, yaw, approach, source=source), ""
    except CalibrationError as exc:
        return unvalidated, (f"the fitted grid is invalid ({exc.allowed}; got {exc.field} = {exc.value}): check the "
                             "tower/height labels of the points")


def _shared_targets(station: Station, points: Sequence[TaughtPoint], m: Measured, shared: BoolArray) -> FloatArray:
    """For each shared above pose: the nearest point that stands over its slot's contact point and at least one
    block above it (NaN rows for the others)."""
    out = np.full((len(points), 3), np.nan)
    for i in np.flatnonzero(shared):
        p = points[i]
        contact = np.asarray(station.tower_origins[p.tower]) + p.height * np.asarray(station.height_step)
        out[i] = [contact[0], contact[1], max(float(m.p_world[i, 2]), contact[2] + station.block_size)]
    return out


def _basis(points: Sequence[TaughtPoint], used: BoolArray, i: int) -> str:
    """``"the 8 other contacts"`` / ``"the other 7 contacts and 9 above poses"``: what point ``i`` was compared
    with."""
    n_on = sum(1 for j, p in enumerate(points) if used[j] and j != i and p.k == ON)
    n_above = sum(1 for j, p in enumerate(points) if used[j] and j != i and p.k == ABOVE)
    if n_above == 0:
        return f"the {n_on} other contacts"
    if n_on == 0:
        return f"the {n_above} other above poses"
    return f"the other {n_on} contacts and {n_above} above poses"


@dataclass(frozen=True)
class _Context:
    base: Station
    points: tuple[TaughtPoint, ...]
    m: Measured
    fit: RobustFit
    fitted: FloatArray
    shared: BoolArray
    hard: tuple[str, ...]
    grid_points: dict[Slot, FloatArray]
    named: dict[int, str]
    heads: dict[int, str]


def _reasons(ctx: _Context, suspects: Sequence[int]) -> dict[int, str]:
    """Why each suspect is suspect, and what probably happened."""
    pts, m, th = ctx.points, ctx.m, ctx.fit.thresholds
    gridded = [i for i in range(len(pts)) if not np.isnan(ctx.fitted[i]).any() and not ctx.shared[i]]
    slots = [(p.tower, p.height, p.k) for p in pts]
    where = {g: n for n, g in enumerate(gridded)}
    robot = load_ur3(ctx.base.tool, ctx.base.limits, ctx.base.robot)
    what = diagnose(robot, ctx.base.T_world_base, [slots[i] for i in gridded],
                    [pts[i].q for i in gridded], m.p_world[gridded], ctx.fit.rot_deg[gridded], ctx.fitted[gridded],
                    ctx.grid_points,
                    [where[i] for i in suspects if i in where], ctx.fit.yaw, th.mm, th.deg,
                    [f"{pts[i].label}" for i in gridded])
    out: dict[int, str] = {}
    for i in suspects:
        p = pts[i]
        if np.isnan(ctx.fitted[i]).any():
            out[i] = ctx.hard[i]
            continue
        parts = []
        dev = float(np.linalg.norm(m.p_world[i] - ctx.fitted[i])) * 1e3
        if i in ctx.heads:  # a named point the fit had to keep: where the others put it, not this fit
            parts.append(ctx.heads[i])
        elif ctx.shared[i]:
            heights = ", ".join(str(h + 1) for h in p.shared)
            parts.append(f"the above pose shared by heights {heights} of tower {p.tower + 1} is {dev:.1f} mm from "
                         "standing over this contact point at least one block above it")
        elif ctx.fit.used[i] and not ctx.fit.removable[i]:
            parts.append(f"{dev:.1f} mm from the grid (kept in the fit: the other points do not determine it without "
                         "this one)")
        else:
            parts.append(f"{dev:.1f} mm from the grid fitted to {_basis(pts, ctx.fit.used, i)}")
        if i in ctx.named:  # the consensus said what is wrong with it
            out[i] = "; ".join([*parts, ctx.named[i]])
            continue
        if ctx.fit.rot_deg[i] > th.deg and m.tilt_deg[i] <= MAX_TILT_DEG:
            yaw_dev = math.degrees(float(wrap_angle(m.heading[i] - ctx.fit.yaw)))
            parts.append(f"the tool is turned {ctx.fit.rot_deg[i]:.1f} deg from the grid pose (tilt "
                         f"{m.tilt_deg[i]:.1f} deg, heading {yaw_dev:+.1f} deg)")
        if i in where:
            parts.append(what[where[i]])
        if ctx.hard[i]:
            parts.append(ctx.hard[i])
        out[i] = "; ".join(parts)
    return out


def fit_station(base: Station, taught: TaughtPoints | Sequence[TaughtPoint], name: str | None = None,
                source: str = "<memory>", tol_mm: float | None = None, tol_deg: float | None = None,
                accept: Collection[tuple[int, int]] = ()) -> CalibrationFit:
    """Fit the grid of ``base`` (tower origins, height step, approach, tool yaw) to taught poses, robustly.

    Which point is grossly wrong is decided first, on all the evidence (:mod:`ur3hanoi.calibrate.consensus`): the
    one named is left out (the robust fit never uses it), or, when it is its tower's only contact or the points
    cannot tell which of several is wrong, the fit is refused (:attr:`CalibrationFit.problem`).

    Args:
        base: calibration providing everything not fitted (robot base, tool offset, blocks, home, counts, layout).
        taught: the taught points (joint angles [rad]).
        name: name of the new station (default: the base's).
        source: recorded as the new station's ``source`` (the output file's path).
        tol_mm, tol_deg: fixed suspect thresholds [mm], [deg] instead of the ones derived from the data (see
            :mod:`ur3hanoi.calibrate.robust`).
        accept: ``(tower, height)`` slots (0-based) whose contact poses the student vouches for: never left out,
            and their towers placed where they say even far from the base's layout.

    Raises:
        TaughtPointsError: no points, a table whose shape is not the base's grid, or too little left to fit.
    """
    if isinstance(taught, TaughtPoints):
        points, where, missing, shape = taught.points, taught.source, taught.missing, taught.shape
    else:
        points, where, missing, shape = tuple(taught), "<memory>", (), None
    if not points:
        raise fail(where, "no taught points")
    if shape is not None and shape != (base.n_towers, base.n_heights):
        raise fail(where, f"the table has {shape[0]} towers x {shape[1]} heights, the base calibration "
                           f"{printable(base.source)} {base.n_towers} x {base.n_heights}: use a base with the table's "
                           "grid")

    prep = prepare(base, points, accept)
    slots = [(p.tower, p.height, p.k) for p in points]
    candidates = prep.candidates.copy()
    model = choose_model(base, [s for s, c in zip(slots, candidates, strict=True) if c])
    if model is None:
        raise underdetermined(where, base, points, candidates, prep.hard)
    fit = robust_fit(base, model, prep.safe_slots, prep.m, candidates, tol_mm, tol_deg)
    c = prep.consensus
    if c.kind in ("undecided", "unexplained") and _scatter(c, fit, prep):
        c = replace(c, kind="agree", wrong=(), alone=False, chosen=c.whole)
    named = {i: named_text(prep.evidence, c, i, points) for i in c.wrong}
    refused = c.kind == "undecided" or (c.kind == "named" and c.alone)
    problem = refusal(prep.evidence, c, points) if refused else ""
    heads = {i: where_text(prep.evidence, c, i) for i in c.wrong} if refused else {}
    agreeing = candidates & ~np.isin(np.arange(len(points)), c.wrong if c.kind == "named" else ())
    if c.kind == "named" and not c.alone and fit.used[c.wrong[0]]:
        candidates = agreeing  # left out from the start: it never drags the fit
        model = choose_model(base, [s for s, k in zip(slots, candidates, strict=True) if k])
        assert model is not None  # its tower has another contact
        fit = robust_fit(base, model, prep.safe_slots, prep.m, candidates, tol_mm, tol_deg)
    if c.kind in ("agree", "named") and not refused and (_bends(fit, prep, agreeing) or _tilt_only(fit, prep,
                                                                                                  agreeing)):
        # The finer pruning left out points that agree with the rest, and the grid moved more than the
        # always-flagged distance from them: they agree, so they all stay.
        candidates = agreeing
        model = choose_model(base, [s for s, k in zip(slots, candidates, strict=True) if k])
        assert model is not None
        fit = robust_fit(base, model, prep.safe_slots, prep.m, candidates, tol_mm, tol_deg, prune=False)
    station, invalid = _station(base, model, fit.solution, fit.yaw, source)
    if name is not None:
        station = replace(station, name=name)
    ctx = _judged(base, station, points, prep.m, fit, prep.safe_slots, prep.off_grid, prep.shared, prep.hard, named,
                  heads)
    return _with_consensus(_calibration_fit(ctx, station, model, candidates, missing, problem or invalid), prep, c)


def _with_consensus(fit: CalibrationFit, prep: Prepared, c: Consensus) -> CalibrationFit:
    """The fit with what the consensus said: each point's distance from where the others put it, the points taken
    on the student's word, and, when no single point explains a disagreement the robust fit left, why."""
    accepted = tuple((int(i), math.nan) for i in np.flatnonzero(prep.evidence.accepted))
    usable = np.array(fit.used) & prep.candidates
    single = single_pose_towers([(p.tower, p.height, p.k) for p in fit.points], usable)
    lean = {ch.index: ch.value for ch in judge(prep.evidence, usable).checks if ch.what == "lean"}
    out = replace(fit, consensus=c.kind, named=c.wrong, off_mm=c.chosen.off_mm, judged_by=c.chosen.by,
                  accepted=accepted,
                  single_pose=tuple((t, i, lean.get(t, math.nan)) for t, i in sorted(single.items())))
    if c.kind == "unexplained" and fit.sound:
        problem = unexplained(prep.evidence, judge(prep.evidence, usable), fit.points)  # the robust fit's choice
        if problem:
            out = replace(out, problem=problem, warnings=(*fit.warnings, f"the fit is not sound: {problem}"))
    return out


def _judged(base: Station, station: Station, points: Sequence[TaughtPoint], m: Measured, fit: RobustFit,
            safe_slots: Sequence[tuple[int, int, int]], off_grid: BoolArray, shared: BoolArray,
            hard: tuple[str, ...], named: dict[int, str], heads: dict[int, str]) -> _Context:
    """Every point against the fitted grid: where the grid puts it (shared "above" poses and off-grid points by
    the final station), its deviation, and the context the explanations need."""
    fitted = fit.solution.points(safe_slots)
    fitted[off_grid] = np.nan
    shared_t = _shared_targets(station, points, m, shared)
    fitted[shared] = shared_t[shared]
    grid_points = {(t, h, k): fit.solution.point((t, h, k)) for t in range(base.n_towers)
                   for h in range(base.n_heights) for k in (ON, ABOVE)}
    return _Context(base=base, points=tuple(points), m=m, fit=fit, fitted=fitted, shared=shared, hard=hard,
                    grid_points=grid_points, named=named, heads=heads)


def _calibration_fit(ctx: _Context, station: Station, model: GridModel, candidates: BoolArray,
                     missing: tuple[Slot, ...], problem: str) -> CalibrationFit:
    """The suspects (worst first, each with its reason), the soundness verdict and the report of the fit."""
    points, m, fit, fitted = ctx.points, ctx.m, ctx.fit, ctx.fitted
    residuals = np.linalg.norm(m.p_world - fitted, axis=1) * 1e3
    # Shared poses and points left out are judged by their distance from the final grid.
    dev_mm = np.where(fit.used & fit.removable, fit.deviation_mm, residuals)
    severity = np.maximum(dev_mm / fit.thresholds.mm, fit.rot_deg / fit.thresholds.deg)
    named = np.isin(np.arange(len(points)), list(ctx.named))
    is_suspect = named | np.array([bool(h) for h in ctx.hard])
    if not ctx.heads:  # when the named points had to stay in the fit, it judges the others wrongly: not shown
        is_suspect |= (~fit.used & candidates) | (severity > 1.0)
    order = sorted(np.flatnonzero(is_suspect), key=lambda i: -np.nan_to_num(severity[i], nan=np.inf))
    # Those that cannot take part first (a pose 117 deg from tool down is wrong whatever the others say), then the
    # one the consensus named, then the points the fit left out, then the rest, each worst first.
    hard = [i for i in order if ctx.hard[i]]
    named_first = [i for i in ctx.named if i in order and i not in hard]
    rest = [i for i in order if i not in hard and i not in ctx.named]
    order = hard + named_first + [i for i in rest if not fit.used[i]] + [i for i in rest if fit.used[i]]
    reasons = _reasons(ctx, [int(i) for i in order])
    suspects = tuple(
        Suspect(index=int(i), tower=points[i].tower, height=points[i].height, k=points[i].k, field=points[i].where,
                error_mm=float(residuals[i]), severity=float(np.nan_to_num(severity[i], nan=np.inf)),
                reason=reasons[int(i)])
        for i in order)

    if not problem:
        problem = _soundness(fit, candidates, dev_mm, points)
    warnings = [f"{s.label} [{s.field}]: {s.reason}" for s in suspects]
    if problem:
        warnings.append(f"the fit is not sound: {problem}")
    yaw_dev = np.degrees(wrap_angle(m.heading - fit.yaw))
    idx = np.flatnonzero(fit.used)
    return CalibrationFit(
        station=station, points=tuple(points), measured=m.p_world, fitted=fitted, residuals_mm=residuals,
        yaw_dev_deg=yaw_dev, tilt_deg=m.tilt_deg, rot_deg=fit.rot_deg, fitted_params=model.params,
        dof=3 * len(idx) - model.n_unknowns, used=tuple(bool(u) for u in fit.used),
        status=tuple("suspect" if s else "ok" for s in is_suspect), suspects=suspects, thresholds=fit.thresholds,
        missing=missing, problem=problem, warnings=tuple(warnings),
    )


def _bends(fit: RobustFit, prep: Prepared, candidates: BoolArray) -> bool:
    """Whether the fit puts a candidate it left out farther from its slot than the always-flagged distance (an
    above pose: off its tower's line)."""
    d = prep.m.p_world - fit.solution.points(prep.safe_slots)
    for i in np.flatnonzero(candidates & ~fit.used):
        on = prep.safe_slots[i][2] == ON
        if float(np.linalg.norm(d[i] if on else d[i, :2])) * 1e3 > (CONTACT_FLAG_MM if on else ABOVE_FLAG_LINE_MM):
            return True
    return False


def _scatter(c: Consensus, fit: RobustFit, prep: Prepared) -> bool:
    """Whether what the consensus could not pin on one point is the station's scatter, as the audit judges it
    (``check-table --fit`` calls such a table clean, and the two must agree): only contacts the others check were
    off, each at most :data:`~ur3hanoi.calibrate.consensus.SCATTER_SHARE` of the always-flagged distance, or the
    robust fit leaves every contact within it (a contact it left out: of the grid fitted without it)."""
    over = [ch for ch in c.whole.checks if ch.over and not ch.soft]
    if not over or any(ch.what != "point" for ch in over):
        return False
    if all(ch.share <= SCATTER_SHARE for ch in over):  # contacts up to 12 mm off the others' grid: real scatter
        return True
    residual = np.linalg.norm(prep.m.p_world - fit.solution.points(prep.safe_slots), axis=1) * 1e3
    dev = np.where(fit.used & fit.removable, fit.deviation_mm, residual)
    on = prep.candidates & np.array([s[2] == ON for s in prep.safe_slots])
    return bool(np.all(dev[on] <= CONTACT_FLAG_MM))


def _tilt_only(fit: RobustFit, prep: Prepared, candidates: BoolArray) -> bool:
    """Whether the fit left out a contact the consensus kept for its orientation alone: its tower tilted alike on
    every point (the student's wrist there: issue 37), which the consensus judges per tower."""
    d = np.linalg.norm(prep.m.p_world - fit.solution.points(prep.safe_slots), axis=1) * 1e3
    left = np.flatnonzero(candidates & ~fit.used)
    return any(prep.safe_slots[i][2] == ON and fit.rot_deg[i] > fit.thresholds.deg and d[i] <= fit.thresholds.mm
               for i in left)


def _soundness(fit: RobustFit, candidates: BoolArray, dev_mm: FloatArray, points: Sequence[TaughtPoint]) -> str:
    """Why the remaining fit cannot be trusted ("" if it can)."""
    n = int(candidates.sum())
    left_out = int((candidates & ~fit.used).sum())
    over = fit.used & (dev_mm > fit.thresholds.mm)
    if left_out >= max(1, (n - 1) // 2) and over.any():
        return (f"{left_out} of {n} points left out and more still disagree with the grid: check the base "
                "calibration's robot base and tool, and the tower/height labels")
    # The others do not determine the grid without them (pruning drops the others): judged by the always-flagged
    # distance, not the fit's few-mm floors (a contact and the above pose over it disagree by twice the recording
    # noise, 1-3 mm each, and the calibration averages them).
    flag = np.array([CONTACT_FLAG_MM if p.k == ON else ABOVE_FLAG_LINE_MM for p in points])
    stuck = fit.used & (dev_mm > flag) & ~fit.removable
    if stuck.any():
        worst = sorted(np.flatnonzero(stuck), key=lambda i: -dev_mm[i])
        named = [f"{slot_text(points[i])} ({dev_mm[i]:.1f} mm)" for i in worst[:3]]
        more = f" and {len(worst) - 3} more" if len(worst) > 3 else ""
        return (f"{', '.join(named)}{more}, which the fit cannot do without, {'is' if len(worst) == 1 else 'are'} "
                f"more than the always-flagged {CONTACT_FLAG_MM:g} mm ({ABOVE_FLAG_LINE_MM:g} mm for an above pose) "
                f"off the grid: re-record {'it' if len(worst) == 1 else 'them'} or add points")
    return ""


__all__ = ["fit_station"]
