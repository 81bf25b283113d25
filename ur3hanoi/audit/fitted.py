"""Audit a hand-recorded table on its own (``check-table --fit``), by the rule of :mod:`ur3hanoi.audit.rule`.

1. Every entry present is measured by FK with the robot base and tool of a base calibration.
2. The grid (one origin per tower, one step between levels, free in all three axes) is fitted to the **contacts**
   only, robustly (:func:`ur3hanoi.calibrate.robust.robust_fit`, positions only): each contact's deviation is its
   distance from the grid fitted to the others (leave one out), so one gross error never drags the fit or hides
   behind the entries it shares unknowns with. Above poses are recorded anywhere 15-60 mm over the stacks: they
   are judged against the grid, not fitted.
3. The layout is read off the fitted step: levels stepping sideways are the flat Gazebo layout, stepping up a
   stacked station, whatever ``--base`` says (the note names ``--base lab_sim`` when the two differ).
4. The table's own suction axis is the robust mean of its contacts' axes (:func:`~ur3hanoi.audit.rule.
   table_axis`); each contact's tilt is its angle from it. The heading about the axis is never judged.
5. Each contact and above pose is judged by the rule; flagged contacts are explained (a copied entry, swapped
   entries, a pose recorded in another slot, or a typo in one joint when that one change explains most of a large
   error: :func:`ur3hanoi.calibrate.explain.diagnose_contacts`).

A contact that alone fixes its tower's line (the only one of its tower) cannot be checked: it is ``unchecked``, and
the note says which entry to record to check it. A table whose contacts cannot be checked at all, or that does
not fit one grid, has :attr:`~ur3hanoi.audit.report.AuditReport.problem` set (exit 1) saying what to do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ur3hanoi.audit.report import AuditEntry, AuditReport
from ur3hanoi.audit.rule import (
    ABOVE_CLEAR_MM,
    CONTACT_FLAG_MM,
    CONTACT_OK_MM,
    TILT_FLAG_DEG,
    TILT_OK_DEG,
    AuditRule,
    Verdict,
    angle_deg,
    derive_rule,
    judge_above,
    judge_contact,
    table_axis,
)
from ur3hanoi.calibrate.explain import diagnose_contacts
from ur3hanoi.calibrate.grid_fit import GridModel, Measured, measure
from ur3hanoi.calibrate.result import Suspect
from ur3hanoi.calibrate.robust import RobustFit, Thresholds, robust_fit
from ur3hanoi.calibrate.taught import taught_from_recorded
from ur3hanoi.errors import TaughtPointsError, printable
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, pose_label
from ur3hanoi.tables import RecordedTable, Slot


def _grid_like(base: Station, n_towers: int, n_heights: int) -> Station:
    """``base`` with ``n_towers`` x ``n_heights`` (extra towers continue its tower row): the start of a fit."""
    origins = [np.asarray(o, dtype=float) for o in base.tower_origins[:n_towers]]
    step = (origins[-1] - origins[-2]) if len(origins) > 1 else np.array([0.0, 3 * base.block_size, 0.0])
    while len(origins) < n_towers:
        origins.append(origins[-1] + step)
    return replace(base, tower_origins=tuple((float(x), float(y), float(z)) for x, y, z in origins),
                   n_heights=n_heights)


def _xyz(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])


def _layout_note(base: Station, layout: str, step: np.ndarray, fitted: bool) -> str:
    if not fitted:
        return (f"every tower has one contact only: the step between levels is taken from {printable(base.source)} "
                f"({base.layout} layout)")
    way = "sideways" if layout == "flat" else "up"
    note = f"the table's levels step {np.linalg.norm(step) * 1e3:.1f} mm {way}: a {layout} layout"
    if layout != base.layout:
        note += (f" (the base {printable(base.source)} is {base.layout}; audited as {layout} all the same: "
                 + ("the course's Gazebo tables are flat, `--base lab_sim` gives their world frame)" if layout == "flat"
                    else "pass the station's own calibration with --base for its world frame)"))
    return note


@dataclass(frozen=True)
class _Fitted:
    """A table's entries measured by FK and its grid fitted robustly to the contacts (step 1-4 of the module
    docstring): what judging the entries reads. Indices ``i`` run over ``slots`` (the entries present), ``j`` over
    the contacts used (``c_idx``)."""

    table: RecordedTable
    base: Station
    slots: list[Slot]
    qs: np.ndarray  # (N, 6) [rad]
    m: Measured  # every entry present
    mc: Measured  # the contacts within the joint limits
    in_limits: np.ndarray  # (N,) bool
    c_idx: np.ndarray  # (C,) indices of the contacts in slots
    c_slots: list[Slot]
    tilt: np.ndarray  # (N,) [deg] from the table's axis
    axis: np.ndarray  # the table's own suction axis [world]
    fit: RobustFit
    layout: str
    step_fitted: bool
    checkable: np.ndarray  # (C,) bool
    rule: AuditRule
    field: dict[Slot, str]

    @property
    def limits_why(self) -> str:
        return f"its joint angles are outside the joint limits of {printable(self.base.source)}: left out of the fit"


def audit_table(table: RecordedTable, base: Station, tol_mm: float | None = None, tol_deg: float | None = None
                ) -> AuditReport:
    """Audit ``table`` on its own by the rule of :mod:`ur3hanoi.audit.rule` (see the module docstring).

    Args:
        table: the recorded table.
        base: the calibration giving robot base, tool and home (its grid is replaced by the one fitted).
        tol_mm, tol_deg: fixed flag thresholds [mm], [deg] instead of 8 mm / 5 deg.

    Raises:
        TaughtPointsError: some tower has no usable contact pose (the message says which, and what is needed), or
            the values are not radians.
    """
    ctx = _fit_contacts(table, base, tol_mm, tol_deg)
    entries: dict[Slot, AuditEntry] = {}
    verdicts: dict[Slot, Verdict] = {}
    _judge_contacts(ctx, entries, verdicts)
    _judge_the_rest(ctx, entries, verdicts)
    reasons = _contact_reasons(table, base, ctx.slots, ctx.qs, ctx.m.p_world, ctx.tilt, ctx.axis, ctx.c_idx, ctx.fit,
                               verdicts, entries, ctx.rule, ctx.field)
    for s, why in reasons.items():
        entries[s] = replace(entries[s], status="suspect" if verdicts[s].status == "flagged" else verdicts[s].status,
                             reason=why)
    _on_above_swaps(entries, ctx.rule)
    return _report(ctx, entries, verdicts)


def _fit_contacts(table: RecordedTable, base: Station, tol_mm: float | None, tol_deg: float | None) -> _Fitted:
    """Steps 1-4 of the module docstring: measure, fit the grid to the contacts, read the layout and the axis."""
    taught_from_recorded(table)  # the values must look like radians
    n_t, n_h = table.n_towers, table.n_heights
    grid = _grid_like(base, n_t, n_h)
    slots: list[Slot] = [(t, h, k) for t in range(n_t) for h in range(n_h) for k in (ON, ABOVE)
                         if table.present[t, h, k]]
    qs = np.array([table.q[s] for s in slots], dtype=float).reshape(-1, 6)
    m = measure(grid, [tuple(float(v) for v in q) for q in qs])
    axes = m.R_world[:, :, 2]
    in_limits = np.array([grid.limits.within_position(q) for q in qs], dtype=bool)
    c_idx = np.flatnonzero(np.array([s[2] == ON for s in slots], dtype=bool) & in_limits)
    c_slots = [slots[i] for i in c_idx]
    lacking = [t + 1 for t in range(n_t) if not any(s[0] == t for s in c_slots)]
    if lacking:
        raise TaughtPointsError(
            f"{printable(table.source)}: too little left to fit the grid: it needs a usable contact ('on') pose on "
            f"every tower ({n_t} towers), within the joint limits of {printable(base.source)}; tower(s) "
            f"{', '.join(map(str, lacking))} have none: record one", source=table.source)

    model = GridModel(n_t, (0, 1, 2), False)
    step_fitted = model.determined_by(c_slots)
    if not step_fitted:
        model = GridModel(n_t, (), False)
    axis = table_axis(axes[c_idx])
    tilt = angle_deg(axes, axis)
    mc = Measured(p_world=m.p_world[c_idx], R_world=m.R_world[c_idx], heading=m.heading[c_idx],
                  tilt_deg=m.tilt_deg[c_idx])
    # Contacts within the warning distance of the grid of the others (5 sigma of the data, clamped to 5-8 mm) stay
    # in the fit: one further off would drag its neighbours. Positions only: the axis is checked on its own.
    fit = robust_fit(grid, model, c_slots, mc, np.ones(len(c_idx), dtype=bool), tol_mm=tol_mm, tol_deg=1.0,
                     angle_deg=np.zeros(len(c_idx)), mm_range=(CONTACT_OK_MM, CONTACT_FLAG_MM))
    sol = fit.solution
    layout = (("flat" if math.hypot(sol.step[0], sol.step[1]) > abs(sol.step[2]) else "stacked") if step_fitted
              else base.layout)
    checkable = fit.removable | ~fit.used
    rule = derive_rule(np.linalg.norm(fit.deviation[checkable], axis=1) * 1e3, tilt[c_idx], tol_mm, tol_deg)
    return _Fitted(table=table, base=base, slots=slots, qs=qs, m=m, mc=mc, in_limits=in_limits, c_idx=c_idx,
                   c_slots=c_slots, tilt=tilt, axis=axis, fit=fit, layout=layout, step_fitted=step_fitted,
                   checkable=checkable, rule=rule,
                   field={s: f"{table.key}[{s[0]}][{s[1]}][{s[2]}]" for s in slots})


def _judge_contacts(ctx: _Fitted, entries: dict[Slot, AuditEntry], verdicts: dict[Slot, Verdict]) -> None:
    """Judge every contact the fit used by its deviation from the grid fitted to the others (step 5)."""
    dev, m, qs, tilt, field = ctx.fit.deviation, ctx.m, ctx.qs, ctx.tilt, ctx.field
    for j, i in enumerate(ctx.c_idx):
        s = ctx.slots[i]
        d = dev[j] * 1e3
        if ctx.checkable[j]:
            v = judge_contact(math.hypot(d[0], d[1]), float(d[2]), float(tilt[i]), ctx.rule)
        else:
            v = judge_contact(0.0, 0.0, float(tilt[i]), ctx.rule)
            if v.status == "ok":
                alone = (f"the only contact of tower {s[0] + 1}: nothing else fixes its line"
                         if sum(c[0] == s[0] for c in ctx.c_slots) == 1 else
                         f"the grid cannot be fitted without it (with the contacts kept, it alone fixes tower "
                         f"{s[0] + 1}'s line or the step between levels)")
                v = Verdict("unchecked", 0.0, f"{alone}, so its position cannot be checked (record another height "
                                              f"of tower {s[0] + 1} to check it)")
        verdicts[s] = v
        entries[s] = AuditEntry(
            tower=s[0], height=s[1], k=s[2], field=field[s],
            error_mm=float(np.linalg.norm(d)), rot_deg=math.nan, tilt_deg=float(tilt[i]),
            status="suspect" if v.status == "flagged" else v.status, reason=v.why, q=tuple(float(x) for x in qs[i]),
            point_m=_xyz(m.p_world[i]), fitted_m=_xyz(m.p_world[i] - dev[j]),
            off_line_mm=math.hypot(d[0], d[1]) if ctx.checkable[j] else math.nan,
            off_level_mm=float(d[2]) if ctx.checkable[j] else math.nan)


def _judge_the_rest(ctx: _Fitted, entries: dict[Slot, AuditEntry], verdicts: dict[Slot, Verdict]) -> None:
    """Judge the contacts outside the joint limits and every above pose against the fitted grid (step 5)."""
    table, sol, qs, tilt, field = ctx.table, ctx.fit.solution, ctx.qs, ctx.tilt, ctx.field
    top_z = max(float(sol.point((t, h, ON))[2]) for t in range(table.n_towers)
                for h in range(table.n_heights))  # the top of any stack
    for i, s in enumerate(ctx.slots):
        if s in entries:
            continue
        c = sol.point((s[0], s[1], ON))
        p = ctx.m.p_world[i]
        if s[2] == ON:  # outside the joint limits
            d = (p - c) * 1e3
            entries[s] = AuditEntry(
                tower=s[0], height=s[1], k=s[2], field=field[s], error_mm=float(np.linalg.norm(d)), rot_deg=math.nan,
                tilt_deg=float(tilt[i]), status="suspect", q=tuple(float(x) for x in qs[i]), point_m=_xyz(p),
                fitted_m=_xyz(c), off_line_mm=math.hypot(d[0], d[1]), off_level_mm=float(d[2]),
                reason=ctx.limits_why)
            verdicts[s] = Verdict("flagged", math.inf, ctx.limits_why)
            continue
        off_line = math.hypot(float(p[0] - c[0]), float(p[1] - c[1])) * 1e3
        over_top, over_contact = (float(p[2]) - top_z) * 1e3, float(p[2] - c[2]) * 1e3
        v = judge_above(off_line, over_top, over_contact)
        if not ctx.in_limits[i]:
            v = Verdict("flagged", math.inf, "; ".join(x for x in (v.why, ctx.limits_why) if x))
        if v.status == "flagged" and table.present[s[0], s[1], ON] and np.array_equal(qs[i], table.q[s[0], s[1], ON]):
            v = replace(v, why=f"{v.why}; it holds the joint values of {pose_label(s[0], s[1], ON)}: a copied entry")
        shared = table.shared_with(s[0], s[1])
        if shared and v.why:
            v = replace(v, why=f"the above pose shared by heights {', '.join(str(h + 1) for h in shared)} of tower "
                               f"{s[0] + 1}: {v.why}")
        target = np.array([c[0], c[1], max(float(p[2]), top_z + ABOVE_CLEAR_MM * 1e-3)])
        verdicts[s] = v
        entries[s] = AuditEntry(
            tower=s[0], height=s[1], k=s[2], field=field[s],
            error_mm=float(np.linalg.norm(p - target)) * 1e3, rot_deg=math.nan,
            tilt_deg=float(tilt[i]), status="suspect" if v.status == "flagged" else v.status,
            q=tuple(float(x) for x in qs[i]), point_m=_xyz(p), fitted_m=_xyz(target), off_line_mm=off_line,
            over_top_mm=over_top, over_contact_mm=over_contact, reason=v.why)


def _report(ctx: _Fitted, entries: dict[Slot, AuditEntry], verdicts: dict[Slot, Verdict]) -> AuditReport:
    """Every slot in ``Q`` order (missing ones included), suspects and warnings worst first, notes and problem."""
    table, base, fit, rule = ctx.table, ctx.base, ctx.fit, ctx.rule
    rows = tuple(entries.get((t, h, k)) or AuditEntry(t, h, k, f"{table.key}[{t}][{h}][{k}]", math.nan, math.nan,
                                                       math.nan, "missing")
                 for t in range(table.n_towers) for h in range(table.n_heights) for k in (ON, ABOVE))

    def listed(status: str) -> tuple[Suspect, ...]:
        chosen = sorted((e for e in rows if e.status == status),
                        key=lambda e: -verdicts[(e.tower, e.height, e.k)].severity)
        return tuple(Suspect(tower=e.tower, height=e.height, k=e.k, field=e.field, error_mm=e.error_mm,
                             reason=e.reason) for e in chosen)

    sol = fit.solution
    notes, problem = _notes_and_problem(base, ctx.layout, sol.step, ctx.step_fitted, ctx.axis, rows, rule,
                                        len(ctx.c_idx), int(ctx.checkable.sum()), sol.origins)
    used = np.flatnonzero(fit.used)
    resid = (ctx.mc.p_world[used] - sol.points([ctx.c_slots[j] for j in used])) * 1e3
    rms = float(np.sqrt(np.mean(np.sum(resid**2, axis=1)))) if len(used) else math.nan
    reference = (f"grid fitted to {len(used)} of the table's {len(ctx.c_idx)} contacts by robust least squares (robot "
                 f"base, tool and home of {printable(base.source)}); above poses judged against it")
    return AuditReport(reference=reference, fitted=True, entries=rows, suspects=listed("suspect"), rms_mm=rms,
                       points_used=len(used),
                       thresholds=Thresholds(mm=rule.flag_mm, deg=rule.flag_deg, sigma_mm=rule.sigma_mm,
                                             sigma_deg=rule.sigma_deg, derived=not rule.fixed),
                       shared_above=table.shared_above, problem=problem, rule=rule, warnings=listed("warn"),
                       notes=tuple(notes), layout=ctx.layout)


def _contact_reasons(table: RecordedTable, base: Station, slots: list[Slot], qs: np.ndarray, p_world: np.ndarray,
                     tilt: np.ndarray, axis: np.ndarray, c_idx: np.ndarray, fit: RobustFit,
                     verdicts: dict[Slot, Verdict], entries: dict[Slot, AuditEntry], rule: AuditRule,
                     field: dict[Slot, str]) -> dict[Slot, str]:
    """Why each flagged or warned contact is off, with what probably happened for the flagged ones."""
    c_slots = [slots[i] for i in c_idx]
    bad = [j for j, s in enumerate(c_slots) if verdicts[s].status in ("flagged", "warn", "unchecked")]
    flagged = [j for j in bad if verdicts[c_slots[j]].status == "flagged"]
    targets = np.array([entries[s].fitted_m for s in c_slots]).reshape(-1, 3)
    grid_points = {(t, h, ON): fit.solution.point((t, h, ON)) for t in range(table.n_towers)
                   for h in range(table.n_heights)}
    labels = [f"{pose_label(*s)} ({field[s]})" for s in c_slots]
    robot = load_ur3(base.tool, base.limits, base.robot)
    what = diagnose_contacts(robot, base.T_world_base, c_slots, [qs[i] for i in c_idx],
                             p_world[c_idx], tilt[c_idx], targets, grid_points, flagged, axis, rule.flag_mm,
                             rule.flag_deg, CONTACT_OK_MM, TILT_OK_DEG, labels)
    out: dict[Slot, str] = {}
    for j in bad:
        s = c_slots[j]
        v = verdicts[s]
        if v.status == "unchecked":
            out[s] = v.why
            continue
        n_other = int(fit.used.sum()) - int(fit.used[j])
        head = (f"suction point {entries[s].error_mm:.1f} mm from where the grid fitted to the other {n_other} "
                f"contacts puts it")
        parts = [f"{head} ({v.why})" if entries[s].error_mm > rule.warn_mm else v.why]
        if what.get(j):
            parts.append(what[j])
        out[s] = "; ".join(parts)
    return out


def _on_above_swaps(entries: dict[Slot, AuditEntry], rule: AuditRule) -> None:
    """Name a slot whose contact and above poses were swapped: the flagged contact is over its level and the above
    pose stands where the contact should be (within the flag distance)."""
    for (t, h, k), e in list(entries.items()):
        above = entries.get((t, h, ABOVE))
        if k != ON or e.status != "suspect" or above is None or above.status != "suspect" or not e.off_level_mm > 0:
            continue
        if math.dist(above.point_m, e.fitted_m) * 1e3 <= rule.flag_mm:
            what = f"on and above swapped with {above.label} ({above.field}): it stands where this contact should be"
            entries[(t, h, k)] = replace(e, reason=f"{e.reason}; {what}")
            entries[(t, h, ABOVE)] = replace(above, reason=f"{above.reason}; on and above swapped with {e.label}")


def _notes_and_problem(base: Station, layout: str, step: np.ndarray, step_fitted: bool, axis: np.ndarray,
                       rows: tuple[AuditEntry, ...], rule: AuditRule, n_contacts: int, n_checkable: int,
                       origins: np.ndarray) -> tuple[list[str], str]:
    notes = [_layout_note(base, layout, step, step_fitted)]
    off_vertical = float(angle_deg(axis.reshape(1, 3), np.array([0.0, 0.0, -1.0]))[0])
    if off_vertical > TILT_FLAG_DEG:
        notes.append(f"the table's own suction axis is {off_vertical:.1f} deg off vertical (every contact is judged "
                     f"against it): is the tool of {printable(base.source)} right?")
    unchecked = [e for e in rows if e.status == "unchecked"]
    if unchecked:
        towers = sorted({e.tower + 1 for e in unchecked})
        notes.append(f"{len(unchecked)} contact(s) cannot be checked ({', '.join(e.label for e in unchecked)}): the "
                     f"grid cannot be fitted without each; record another height of tower(s) "
                     f"{', '.join(map(str, towers))} to check them")
    problem = ""
    block = base.block_size * 1e3
    step_mm = float(np.linalg.norm(step)) * 1e3
    gaps = [(a + 1, b + 1, float(np.linalg.norm((origins[a] - origins[b])[:2])) * 1e3)
            for a in range(len(origins)) for b in range(a + 1, len(origins))]
    close = [g for g in gaps if g[2] < block]
    if step_fitted and step_mm < 0.5 * block:
        problem = (f"the table's levels are {step_mm:.1f} mm apart (a block is {block:.1f} mm): its heights hold "
                   "(nearly) the same pose. Copied entries? Re-record each height")
    elif step_fitted and layout == "stacked" and step[2] < 0:
        problem = (f"the table's levels step {step_mm:.1f} mm down: height 1 (Q[tower][0]) must be the bottom block "
                   "and the last height the top one; reverse the heights")
    elif close:
        a, b, d = close[0]
        problem = (f"towers {a} and {b} stand {d:.1f} mm apart (a block is {block:.1f} mm): copied entries, or "
                   "Q[tower] not in the lab's order? Re-record them")
    elif n_checkable == 0:
        problem = ("no contact can be checked against the others (each alone fixes its tower's line or the step "
                   "between levels): record at least two heights on every tower (all of them are best), then audit "
                   "again")
    else:
        off = [e for e in rows if e.k == ON and e.status == "suspect" and not math.isnan(e.off_line_mm)
               and math.hypot(e.off_line_mm, e.off_level_mm) > rule.flag_mm]
        if n_contacts >= 3 and len(off) > (n_contacts - 1) // 2:
            problem = (f"{len(off)} of {n_contacts} contacts are more than {rule.flag_mm:g} mm off the grid fitted to "
                       "the others: the table does not fit one grid. Check that it follows Q[tower][height][on/above] "
                       f"(height 1 = bottom) and that {printable(base.source)} has the station's robot base and tool "
                       "(--base)")
    return notes, problem


__all__ = ["audit_table"]
