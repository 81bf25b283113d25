"""Audit a lab table, or taught points: every entry's deviation from a grid, and the suspect entries, worst first.

Two references:

- **a calibration** (:func:`check_against`): each entry's FK suction point and tool orientation against the
  station's intended pose; an entry is suspect over fixed tolerances, by default :data:`STRICT_MM` /
  :data:`STRICT_DEG` (1 mm / 0.5 deg): a generated table reproduces its grid to 1e-9 m.
- **the table itself** (:func:`audit_table`): the station grid fitted robustly to the table's entries
  (:func:`ur3hanoi.calibrate.fit_station`: a high-breakdown start, then leave-one-out deletion), with the robot
  base, tool and home of a base calibration and the table's own towers x heights. An entry is suspect over
  thresholds from the data's own robust scatter, ``max(3 mm, 5 sigma)`` and ``max(2 deg, 5 sigma)`` (see
  :mod:`ur3hanoi.calibrate.robust`): hand-recorded poses scatter by a few mm.

Either way the report (:class:`AuditReport`) lists every slot of the table (present or missing), each suspect with
why it is off and what probably happened (a typo in one joint with the recorded and predicted values in deg and
rad, a copied entry, swapped heights or towers, a pose recorded in the wrong slot), and the fit's rms. Calibrating
from taught points gives the same report (:func:`report_from_fit`). :meth:`AuditReport.to_json` is the
command line's ``--json`` object; towers and heights are numbered from 1 in it and in :meth:`AuditReport.text`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ur3hanoi.calibrate import CalibrationFit, fit_station
from ur3hanoi.calibrate.explain import diagnose
from ur3hanoi.calibrate.grid_fit import measure, rotation_error_deg
from ur3hanoi.calibrate.robust import Thresholds
from ur3hanoi.errors import TableError, printable
from ur3hanoi.grid import ABOVE, ON, POSE_NAMES, T_world_tcp
from ur3hanoi.labfile import RecordedTable, Slot
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station
from ur3hanoi.taught import TaughtPoints, taught_from_recorded
from ur3hanoi.waypoints import pose_label

STRICT_MM = 1.0
"""[mm] default position tolerance against a calibration (generated tables)."""
STRICT_DEG = 0.5
"""[deg] default orientation tolerance against a calibration."""
STATUSES: tuple[str, ...] = ("ok", "suspect", "missing")


@dataclass(frozen=True)
class AuditEntry:
    """One slot of the table (or one taught point). ``tower``, ``height``, ``k`` are 0-based indices; lengths [mm],
    angles [deg] (NaN for a missing entry); ``rot_deg`` is the orientation error from the reference pose and
    ``tilt_deg`` the tool's angle from pointing straight down."""

    tower: int
    height: int
    k: int
    field: str
    error_mm: float
    rot_deg: float
    tilt_deg: float
    status: str


@dataclass(frozen=True)
class AuditSuspect:
    """A suspect entry: ``error_mm`` from the reference [mm] and ``reason`` (towers and heights from 1)."""

    tower: int
    height: int
    k: int
    field: str
    error_mm: float
    reason: str

    @property
    def label(self) -> str:
        return pose_label(self.tower, self.height, self.k)


@dataclass(frozen=True)
class AuditReport:
    """The audit of one table or set of taught points.

    Attributes:
        reference: what the entries were compared with, for people.
        fitted: True for a fitted grid, False for a calibration.
        entries: every slot (a table, in ``Q`` order) or point (taught points, in file order).
        suspects: the suspect entries, worst first.
        rms_mm: root mean square deviation of the entries the fit used (fitted grid) or of every entry present
            (calibration) [mm].
        points_used: how many entries the fit used (fitted grid) or were checked (calibration).
        thresholds: when an entry is suspect.
        shared_above: ``(tower, heights)`` groups sharing one above pose (0-based), from a table.
        problem: why the fitted grid cannot be trusted ("" when it can).
    """

    reference: str
    fitted: bool
    entries: tuple[AuditEntry, ...]
    suspects: tuple[AuditSuspect, ...]
    rms_mm: float
    points_used: int
    thresholds: Thresholds
    shared_above: tuple[tuple[int, tuple[int, ...]], ...] = ()
    problem: str = ""

    @property
    def missing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.status == "missing")

    @property
    def failed(self) -> bool:
        """True when some entry is suspect or the fit is not sound."""
        return bool(self.suspects) or bool(self.problem)

    def to_json(self) -> dict[str, Any]:
        """The ``--json`` object: ``{"entries": [...], "suspects": [...], "fit": {...}}``, numbered from 1."""
        return {
            "entries": [{"tower": e.tower + 1, "height": e.height + 1, "pose": POSE_NAMES[e.k], "field": e.field,
                         "error_mm": _num(e.error_mm), "rot_deg": _num(e.rot_deg), "tilt_deg": _num(e.tilt_deg),
                         "status": e.status} for e in self.entries],
            "suspects": [{"tower": s.tower + 1, "height": s.height + 1, "pose": POSE_NAMES[s.k], "field": s.field,
                          "error_mm": _num(s.error_mm), "reason": s.reason} for s in self.suspects],
            "fit": {"rms_mm": _num(self.rms_mm), "points_used": self.points_used,
                    "reference": "grid" if self.fitted else "calibration", "threshold_mm": _num(self.thresholds.mm),
                    "threshold_deg": _num(self.thresholds.deg), "problem": self.problem or None},
        }

    def text(self) -> str:
        """The human-readable report: one row per entry, then missing, shared and suspect entries, then the fit."""
        lines = [f"{'tower':>5} {'height':>6} {'pose':>5} {'pos [mm]':>10} {'rot [deg]':>10} {'tilt [deg]':>10}  "
                 "status"]
        for e in self.entries:
            vals = (f"{'-':>10} {'-':>10} {'-':>10}" if e.status == "missing" or math.isnan(e.error_mm) else
                    f"{e.error_mm:>10.4f} {e.rot_deg:>10.4f} {e.tilt_deg:>10.4f}")
            lines.append(f"{e.tower + 1:>5} {e.height + 1:>6} {POSE_NAMES[e.k]:>5} {vals}  {e.status}")
        missing = self.missing
        if missing:
            names = ", ".join(pose_label(e.tower, e.height, e.k) for e in missing)
            lines.append(f"missing ({len(missing)} of {len(self.entries)}, not used): {names}")
        for t, heights in self.shared_above:
            lines.append(f"shared: tower {t + 1} heights {', '.join(str(h + 1) for h in heights)} share one above "
                         "pose (checked to stand over each contact point, not fitted)")
        if self.suspects:
            lines.append("suspects, worst first:")
            lines += [f"  {s.label} [{s.field}]: {s.reason}" for s in self.suspects]
        present = [e for e in self.entries if e.status != "missing"]
        ok = sum(e.status == "ok" for e in present)
        worst_mm = max((e.error_mm for e in present if not math.isnan(e.error_mm)), default=math.nan)
        worst_deg = max((e.rot_deg for e in present if not math.isnan(e.rot_deg)), default=math.nan)
        lines.append(f"reference: {self.reference}; rms {self.rms_mm:.3f} mm over {self.points_used} entries")
        if self.thresholds.derived:
            lines.append(f"suspect over {self.thresholds.describe()}")
        if self.problem:
            lines.append(f"the fit is not sound: {self.problem}")
        lines.append(f"{ok}/{len(present)} entries within {_tolerance(self.thresholds)} "
                     f"(worst {worst_mm:.4f} mm, {worst_deg:.4f} deg)")
        return "\n".join(lines)


def _num(x: float) -> float | None:
    """A JSON number (rounded to 1e-6), or null for NaN."""
    return None if math.isnan(x) else round(float(x), 6)


def _tolerance(th: Thresholds) -> str:
    if not th.derived:
        return f"{float(th.mm)} mm / {float(th.deg)} deg"
    return f"{th.mm:.1f} mm / {th.deg:.1f} deg"


# ------------------------------------------------------------------------------------------------- references


def report_from_fit(fit: CalibrationFit, reference: str, shape: tuple[int, int] | None = None, key: str = "Q",
                    shared_above: tuple[tuple[int, tuple[int, ...]], ...] = ()) -> AuditReport:
    """The audit report of a calibration fit; with ``shape`` (the towers x heights of table ``key``) every slot is
    listed in ``Q`` order, missing ones included."""
    rows = [AuditEntry(tower=p.tower, height=p.height, k=p.k, field=p.where, error_mm=float(fit.residuals_mm[i]),
                       rot_deg=float(fit.rot_deg[i]), tilt_deg=float(fit.tilt_deg[i]), status=fit.status[i])
            for i, p in enumerate(fit.points)]
    if shape is not None:
        by_slot = {(e.tower, e.height, e.k): e for e in rows}
        rows = [by_slot.get((t, h, k)) or AuditEntry(t, h, k, f"{key}[{t}][{h}][{k}]", math.nan, math.nan, math.nan,
                                                        "missing")
                for t in range(shape[0]) for h in range(shape[1]) for k in (0, 1)]
    suspects = tuple(AuditSuspect(tower=s.tower, height=s.height, k=s.k, field=s.field, error_mm=s.error_mm,
                                  reason=s.reason) for s in fit.suspects)
    return AuditReport(reference=reference, fitted=True, entries=tuple(rows), suspects=suspects, rms_mm=fit.rms_mm,
                       points_used=fit.n_used, thresholds=fit.thresholds, shared_above=shared_above,
                       problem=fit.problem)


def _grid_like(base: Station, n_towers: int, n_heights: int) -> Station:
    """``base`` with ``n_towers`` x ``n_heights`` (extra towers continue its tower row): the start of a fit."""
    origins = [np.asarray(o, dtype=float) for o in base.tower_origins[:n_towers]]
    step = (origins[-1] - origins[-2]) if len(origins) > 1 else np.array([0.0, 3 * base.block_size, 0.0])
    while len(origins) < n_towers:
        origins.append(origins[-1] + step)
    return replace(base, tower_origins=tuple((float(x), float(y), float(z)) for x, y, z in origins),
                   n_heights=n_heights)


def audit_table(table: RecordedTable, base: Station, tol_mm: float | None = None, tol_deg: float | None = None
                ) -> AuditReport:
    """Audit ``table`` on its own: fit the grid to its entries robustly and report every entry's deviation.

    Args:
        table: the recorded table.
        base: the calibration giving robot base, tool offset, home, blocks and layout (its grid is replaced by the
            table's towers x heights and fitted).
        tol_mm, tol_deg: fixed thresholds instead of the ones derived from the data.

    Raises:
        TaughtPointsError: too little is left to fit the grid (the message says what is needed).
    """
    grid = _grid_like(base, table.n_towers, table.n_heights)
    taught = taught_from_recorded(table)
    fit = fit_station(grid, taught, tol_mm=tol_mm, tol_deg=tol_deg)
    reference = (f"grid fitted to the table by robust least squares (robot base, tool and home of "
                 f"{printable(base.source)}), {fit.n_used} of {len(taught.points)} entries used")
    return report_from_fit(fit, reference, (table.n_towers, table.n_heights), table.key, table.shared_above)


def audit_taught(fit: CalibrationFit, taught: TaughtPoints, key: str = "Q",
                 shared_above: tuple[tuple[int, tuple[int, ...]], ...] = ()) -> AuditReport:
    """The report of a calibration from taught points (from table ``key``: its slots listed in ``Q`` order)."""
    reference = f"grid fitted by robust least squares, {fit.n_used} of {len(taught.points)} points used"
    return report_from_fit(fit, reference, taught.shape, key, shared_above)


def check_against(table: RecordedTable, station: Station, tol_mm: float = STRICT_MM, tol_deg: float = STRICT_DEG
                  ) -> AuditReport:
    """Check every entry present in ``table`` against ``station``'s intended poses (FK position [mm] and
    orientation [deg] error; suspect over the tolerances).

    Raises:
        TableError: the table's towers x heights differ from the station's grid.
    """
    if (table.n_towers, table.n_heights) != (station.n_towers, station.n_heights):
        raise TableError(f"{printable(table.source)}: table has {table.n_towers} towers x {table.n_heights} heights, "
                         f"calibration {printable(station.source)} has {station.n_towers} x {station.n_heights}")
    slots: list[Slot] = [(t, h, k) for t in range(table.n_towers) for h in range(table.n_heights) for k in (ON, ABOVE)]
    present = [s for s in slots if table.present[s]]
    qs = [table.q[s] for s in present]
    m = measure(station, qs)
    targets = np.array([T_world_tcp(station, *s).translation for s in present]).reshape(len(present), 3)
    err_mm = np.linalg.norm(m.p_world - targets, axis=1) * 1e3
    rot = rotation_error_deg(m.R_world, station.tool_yaw)
    bad = [i for i in range(len(present)) if err_mm[i] > tol_mm or rot[i] > tol_deg]
    order = sorted(bad, key=lambda i: -max(err_mm[i] / tol_mm, rot[i] / tol_deg))
    grid_points = {s: T_world_tcp(station, *s).translation for s in slots}
    fields = [f"{table.key}[{t}][{h}][{k}]" for t, h, k in present]
    labels = [f"{fields[i]} ({pose_label(*s)})" for i, s in enumerate(present)]
    robot = load_ur3(station.tool, station.limits, station.robot)
    what = diagnose(robot, station.T_world_base, present, qs, m.p_world, rot,
                    targets, grid_points, order, station.tool_yaw, tol_mm, tol_deg, labels)
    src = printable(station.source)
    suspects = tuple(
        AuditSuspect(tower=present[i][0], height=present[i][1], k=present[i][2], field=fields[i],
                     error_mm=float(err_mm[i]),
                     reason=f"{err_mm[i]:.1f} mm / {rot[i]:.2f} deg from the pose of {src} (tolerance {tol_mm:g} mm / "
                            f"{tol_deg:g} deg); {what[i]}")
        for i in order)
    status = {present[i]: ("suspect" if i in bad else "ok", i) for i in range(len(present))}
    entries = []
    for s in slots:
        if s in status:
            st, i = status[s]
            entries.append(AuditEntry(*s, field=fields[i], error_mm=float(err_mm[i]), rot_deg=float(rot[i]),
                                      tilt_deg=float(m.tilt_deg[i]), status=st))
        else:
            entries.append(AuditEntry(*s, field=f"{table.key}[{s[0]}][{s[1]}][{s[2]}]", error_mm=math.nan,
                                      rot_deg=math.nan, tilt_deg=math.nan, status="missing"))
    rms = float(np.sqrt(np.mean(err_mm**2))) if len(present) else math.nan
    return AuditReport(reference=f"calibration {src}", fitted=False, entries=tuple(entries), suspects=suspects,
                       rms_mm=rms, points_used=len(present),
                       thresholds=Thresholds(mm=tol_mm, deg=tol_deg, sigma_mm=math.nan, sigma_deg=math.nan,
                                             derived=False),
                       shared_above=table.shared_above)


def default_base(key: str) -> str:
    """The shipped station whose robot base and tool audit a table key: ``lab_sim`` for ``sim_pos``, else
    ``lab_real``."""
    return "lab_sim" if key == "sim_pos" else "lab_real"


__all__ = [
    "STATUSES",
    "STRICT_DEG",
    "STRICT_MM",
    "AuditEntry",
    "AuditReport",
    "AuditSuspect",
    "audit_table",
    "audit_taught",
    "check_against",
    "default_base",
    "report_from_fit",
]

