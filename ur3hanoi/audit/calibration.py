"""Audit against a calibration's intended poses (generated tables), and the report of a calibration fit.

- :func:`check_against`: each entry's FK suction point and tool orientation against the station's intended pose
  (both points kept on the entry, as ``point_m`` and ``fitted_m``);
  an entry is suspect over fixed tolerances, by default :data:`~ur3hanoi.audit.report.STRICT_MM` /
  :data:`~ur3hanoi.audit.report.STRICT_DEG` (1 mm / 0.5 deg): a generated table reproduces its grid to 1e-9 m.
- :func:`report_from_fit` / :func:`audit_taught`: the report of :func:`ur3hanoi.calibrate.fit_station` (``calibrate
  --taught`` / ``--from-table``).
"""

from __future__ import annotations

import math

import numpy as np

from ur3hanoi.audit.report import STRICT_DEG, STRICT_MM, AuditEntry, AuditReport
from ur3hanoi.calibrate import CalibrationFit
from ur3hanoi.calibrate.explain import diagnose
from ur3hanoi.calibrate.grid_fit import measure, rotation_error_deg
from ur3hanoi.calibrate.result import Suspect
from ur3hanoi.calibrate.robust import Thresholds
from ur3hanoi.calibrate.taught import TaughtPoints
from ur3hanoi.errors import TableError, printable
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, T_world_tcp, pose_label
from ur3hanoi.tables import RecordedTable, Slot


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
    return AuditReport(reference=reference, fitted=True, entries=tuple(rows), suspects=fit.suspects, rms_mm=fit.rms_mm,
                       points_used=fit.n_used, thresholds=fit.thresholds, shared_above=shared_above,
                       problem=fit.problem)


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
        Suspect(tower=present[i][0], height=present[i][1], k=present[i][2], field=fields[i],
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
                                      tilt_deg=float(m.tilt_deg[i]), status=st, q=tuple(float(v) for v in qs[i]),
                                      point_m=_xyz(m.p_world[i]), fitted_m=_xyz(targets[i])))
        else:
            entries.append(AuditEntry(*s, field=f"{table.key}[{s[0]}][{s[1]}][{s[2]}]", error_mm=math.nan,
                                      rot_deg=math.nan, tilt_deg=math.nan, status="missing"))
    rms = float(np.sqrt(np.mean(err_mm**2))) if len(present) else math.nan
    return AuditReport(reference=f"calibration {src}", fitted=False, entries=tuple(entries), suspects=suspects,
                       rms_mm=rms, points_used=len(present),
                       thresholds=Thresholds(mm=tol_mm, deg=tol_deg, sigma_mm=math.nan, sigma_deg=math.nan,
                                             derived=False),
                       shared_above=table.shared_above)


def _xyz(v: np.ndarray) -> tuple[float, float, float]:
    """A point [m] as the three floats of :attr:`AuditEntry.point_m`."""
    return float(v[0]), float(v[1]), float(v[2])


def default_base(key: str) -> str:
    """The shipped station whose robot base and tool audit a table key: ``lab_sim`` for ``sim_pos``, else
    ``lab_real``."""
    return "lab_sim" if key == "sim_pos" else "lab_real"


__all__ = ["audit_taught", "check_against", "default_base", "report_from_fit"]
