"""What a calibration fit gives: the fitted station, every point's residual, and the suspects.

:class:`Suspect` is also what the audit (:mod:`ur3hanoi.audit`) reports: one type for an entry that disagrees
with its reference, whether a fit or a calibration judged it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.robust import Thresholds
from ur3hanoi.calibrate.taught import TaughtPoint
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import POSE_NAMES, pose_label
from ur3hanoi.tables import Slot


@dataclass(frozen=True)
class Suspect:
    """An entry that disagrees with its reference: a taught point or table entry against the grid fitted to the
    other entries (:func:`~ur3hanoi.calibrate.fit.fit_station`, the fitted audit), or a table entry against a
    calibration's intended pose (the audit against a calibration).

    Attributes:
        tower, height, k: its slot, 0-based indices.
        field: where it is in its file (``points[3]``, ``real_pos[1][2][0]``).
        error_mm: its distance from the reference [mm] (a fitted grid: fitted without it); NaN when it has no grid
            slot.
        reason: why it is suspect and what probably happened, for people (towers and heights from 1).
        index: the point's position in :attr:`CalibrationFit.points`; -1 when no fit judged it.
        severity: ``max(error / threshold_mm, orientation error / threshold_deg)`` of a fit, by which its suspects
            sort; NaN when no fit judged it.
    """

    tower: int
    height: int
    k: int
    field: str
    error_mm: float
    reason: str
    index: int = -1
    severity: float = math.nan

    @property
    def label(self) -> str:
        return pose_label(self.tower, self.height, self.k)


@dataclass(frozen=True)
class ResidualRow:
    """One row of the residual report (one taught point). Lengths [mm], angles [deg]; ``tower``, ``height``
    0-based indices."""

    index: int
    tower: int
    height: int
    pose: str
    residual_mm: float
    dx_mm: float
    dy_mm: float
    dz_mm: float
    yaw_dev_deg: float
    tilt_deg: float
    flagged: bool
    field: str = ""
    status: str = "ok"


@dataclass(frozen=True)
class CalibrationFit:
    """Result of :func:`fit_station`; everything a report or a notebook needs.

    Attributes:
        station: the fitted station (base calibration with the new grid and tool yaw).
        points: the taught points, in input order.
        measured: FK suction points, shape (N, 3) [m, world].
        fitted: the fitted grid's suction points for the same slots, shape (N, 3) [m, world] (NaN rows for a
            slot outside the grid; for a shared above pose, the nearest point over its tower).
        residuals_mm: ``|measured - fitted|`` per point [mm], shape (N,).
        yaw_dev_deg: each point's TCP heading minus the fitted tool yaw [deg], shape (N,).
        tilt_deg: each point's tool tilt from pointing straight down [deg], shape (N,).
        rot_deg: each point's orientation error from the grid pose [deg], shape (N,).
        fitted_params: which grid parameters the points determined (others come from the base calibration).
        dof: redundancy of the position fit (3 x points used minus the unknowns); 0 = exact fit.
        used: shape (N,), the points the final fit used.
        status: per point, ``"ok"`` or ``"suspect"``.
        suspects: the suspect points, worst first.
        thresholds: the suspect thresholds.
        missing: the slots a table left empty ``(tower, height, k)`` (0-based).
        problem: why the fit is not sound ("" when it is).
        warnings: one line per suspect (``"<label>: <reason>"``) and the problem, if any.
        consensus: what the choice of the wrong point found (:class:`ur3hanoi.calibrate.consensus.Consensus`'s
            ``kind``: ``agree``, ``named``, ``undecided``, ``unexplained``).
        named: the points it named as wrong (indices, best first).
        off_mm: (N,) each point's distance [mm] from where the other points put it (NaN: nothing could say).
        judged_by: per point, what judged it: ``points``, ``level`` (a tower's only contact: its height against the
            other towers' level) or "".
        accepted: ``(index, mm)`` of the points taken on the student's word (``mm``: NaN, kept for callers of
            issue 33's form: the base's layout is no evidence of where a tower stands).
        single_pose: ``(tower, index, lean)`` of each tower whose place rests on one pose of the fit (index): nothing
            checks it sideways; ``lean`` [deg]: its suction axis from the other towers' (NaN: none to compare).
    """

    station: Station
    points: tuple[TaughtPoint, ...]
    measured: FloatArray
    fitted: FloatArray
    residuals_mm: FloatArray
    yaw_dev_deg: FloatArray
    tilt_deg: FloatArray
    rot_deg: FloatArray
    fitted_params: tuple[str, ...]
    dof: int
    used: tuple[bool, ...]
    status: tuple[str, ...]
    suspects: tuple[Suspect, ...]
    thresholds: Thresholds
    missing: tuple[Slot, ...]
    problem: str
    warnings: tuple[str, ...]
    consensus: str = "agree"
    named: tuple[int, ...] = ()
    off_mm: FloatArray = field(default_factory=lambda: np.zeros(0))
    judged_by: tuple[str, ...] = ()
    accepted: tuple[tuple[int, float], ...] = ()
    single_pose: tuple[tuple[int, int, float], ...] = ()

    @property
    def sound(self) -> bool:
        """True when the fit can be trusted to write a station (see the module docstring)."""
        return not self.problem

    @property
    def n_used(self) -> int:
        return int(sum(self.used))

    @property
    def rms_mm(self) -> float:
        """Root mean square of the residuals of the points used [mm]."""
        used = np.array(self.used)
        return float(np.sqrt(np.mean(self.residuals_mm[used] ** 2))) if used.any() else math.nan

    @property
    def max_mm(self) -> float:
        """Largest residual of the points used [mm]."""
        used = np.array(self.used)
        return float(np.max(self.residuals_mm[used])) if used.any() else math.nan

    def residual_table(self) -> list[ResidualRow]:
        """Per-point rows (``pandas.DataFrame(fit.residual_table())`` works)."""
        d = (self.measured - self.fitted) * 1e3
        return [
            ResidualRow(index=p.index, tower=p.tower, height=p.height, pose=POSE_NAMES[p.k],
                        residual_mm=float(self.residuals_mm[i]), dx_mm=float(d[i, 0]), dy_mm=float(d[i, 1]),
                        dz_mm=float(d[i, 2]), yaw_dev_deg=float(self.yaw_dev_deg[i]),
                        tilt_deg=float(self.tilt_deg[i]), flagged=self.status[i] == "suspect", field=p.where,
                        status=self.status[i])
            for i, p in enumerate(self.points)
        ]


__all__ = ["CalibrationFit", "ResidualRow", "Suspect"]
