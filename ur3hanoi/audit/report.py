"""The audit report of a table or of taught points: every entry, the flagged ones worst first, and the rule used.

:class:`AuditEntry` is one slot (present or missing) with everything a person or a plot needs: the joint values, the
measured suction point and where the reference puts it [m, world], how far it is off (in all, off its tower's line,
off its level) [mm], its tilt [deg], its status and why. :class:`AuditReport` holds the entries, the flagged ones
(``suspects``) and the warnings worst first, and the rule or tolerances they were judged by;
:meth:`AuditReport.to_json` is the command line's ``--json`` object and :meth:`AuditReport.text` its report. Towers
and heights are numbered from 1 in both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from ur3hanoi.audit.rule import AuditRule
from ur3hanoi.calibrate.result import Suspect
from ur3hanoi.calibrate.robust import Thresholds
from ur3hanoi.station.grid import POSE_NAMES, pose_label

STRICT_MM = 1.0
"""[mm] default position tolerance against a calibration (generated tables)."""
STRICT_DEG = 0.5
"""[deg] default orientation tolerance against a calibration."""
STATUSES: tuple[str, ...] = ("ok", "warn", "suspect", "unchecked", "missing")
"""An entry's status: within the rule, warned (the table passes), flagged, not checkable, or missing."""
_NAN3 = (math.nan, math.nan, math.nan)


@dataclass(frozen=True)
class AuditEntry:
    """One slot of the table (or one taught point). ``tower``, ``height``, ``k`` are 0-based indices; lengths [mm],
    angles [deg] (NaN when not measured or not applicable).

    Attributes:
        field: where it is in its file (``real_pos[1][2][0]``).
        error_mm: distance of the suction point from where the reference puts it [mm].
        rot_deg: orientation error from the reference pose, heading included [deg] (a calibration's check; NaN for
            a fitted audit, which never judges the heading).
        tilt_deg: angle of the suction axis from the reference axis [deg]: straight down against a calibration, the
            table's own axis in a fitted audit.
        status: one of :data:`STATUSES`.
        q: the joint values [rad] (``()`` when missing).
        point_m: the measured suction point [m, world].
        fitted_m: where the reference puts it [m, world] (an above pose: the nearest accepted point).
        off_line_mm: horizontal distance from its tower's vertical line (an above pose: its contact's) [mm].
        off_level_mm: a contact's height over its level's (signed) [mm].
        over_top_mm: an above pose's height over the table's top level [mm].
        over_contact_mm: an above pose's height over its own contact level [mm].
        reason: why it is flagged, warned or unchecked ("" when ok).
    """

    tower: int
    height: int
    k: int
    field: str
    error_mm: float
    rot_deg: float
    tilt_deg: float
    status: str
    q: tuple[float, ...] = ()
    point_m: tuple[float, float, float] = _NAN3
    fitted_m: tuple[float, float, float] = _NAN3
    off_line_mm: float = math.nan
    off_level_mm: float = math.nan
    over_top_mm: float = math.nan
    over_contact_mm: float = math.nan
    reason: str = ""

    @property
    def label(self) -> str:
        return pose_label(self.tower, self.height, self.k)

    def to_json(self) -> dict[str, Any]:
        """This entry in ``--json`` form (numbered from 1)."""
        return {"tower": self.tower + 1, "height": self.height + 1, "pose": POSE_NAMES[self.k], "field": self.field,
                "error_mm": _num(self.error_mm), "off_line_mm": _num(self.off_line_mm),
                "off_level_mm": _num(self.off_level_mm), "over_top_mm": _num(self.over_top_mm),
                "over_contact_mm": _num(self.over_contact_mm), "rot_deg": _num(self.rot_deg),
                "tilt_deg": _num(self.tilt_deg), "status": self.status, "reason": self.reason or None,
                "point_m": _vec(self.point_m), "fitted_m": _vec(self.fitted_m)}


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
        rule: the rule a fitted audit judged by (None: fixed tolerances or a calibration fit).
        warnings: entries over a warning threshold but not flagged, worst first (the table passes).
        notes: what else a person should know (the layout detected, unchecked entries and how to check them).
        layout: ``"stacked"`` or ``"flat"`` as seen in the table ("" when not judged).
    """

    reference: str
    fitted: bool
    entries: tuple[AuditEntry, ...]
    suspects: tuple[Suspect, ...]
    rms_mm: float
    points_used: int
    thresholds: Thresholds
    shared_above: tuple[tuple[int, tuple[int, ...]], ...] = ()
    problem: str = ""
    rule: AuditRule | None = None
    warnings: tuple[Suspect, ...] = ()
    notes: tuple[str, ...] = ()
    layout: str = ""

    @property
    def missing(self) -> tuple[AuditEntry, ...]:
        return tuple(e for e in self.entries if e.status == "missing")

    @property
    def failed(self) -> bool:
        """True when some entry is suspect or the fit is not sound."""
        return bool(self.suspects) or bool(self.problem)

    def to_json(self) -> dict[str, Any]:
        """The ``--json`` object: ``{"entries": [...], "suspects": [...], "fit": {...}}``, numbered from 1."""
        def listed(items: tuple[Suspect, ...]) -> list[dict[str, Any]]:
            return [{"tower": s.tower + 1, "height": s.height + 1, "pose": POSE_NAMES[s.k], "field": s.field,
                     "error_mm": _num(s.error_mm), "reason": s.reason} for s in items]

        fit: dict[str, Any] = {
            "rms_mm": _num(self.rms_mm), "points_used": self.points_used,
            "reference": "grid" if self.fitted else "calibration", "threshold_mm": _num(self.thresholds.mm),
            "threshold_deg": _num(self.thresholds.deg), "problem": self.problem or None}
        if self.rule is not None:
            fit.update(layout=self.layout or None, notes=list(self.notes), rule=self.rule.to_json())
        return {"entries": [e.to_json() for e in self.entries], "suspects": listed(self.suspects),
                "warnings": listed(self.warnings), "fit": fit}

    def text(self) -> str:
        """The human-readable report: one row per entry, then missing, shared and suspect entries, then the fit."""
        if self.rule is not None:
            return self._rule_text(self.rule)
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


    def _rule_text(self, rule: AuditRule) -> str:
        """The report of a fitted audit: the entries' distances and tilts, the flagged ones with why, the rule."""
        lines = [f"{'tower':>5} {'height':>6} {'pose':>5} {'off [mm]':>9} {'line [mm]':>9} {'level [mm]':>10} "
                 f"{'over top':>9} {'tilt [deg]':>10}  status"]
        for e in self.entries:
            cells = [_cell(e.error_mm, 9, 2), _cell(e.off_line_mm, 9, 2), _cell(e.off_level_mm, 10, 2),
                     _cell(e.over_top_mm, 9, 1), _cell(e.tilt_deg, 10, 2)]
            lines.append(f"{e.tower + 1:>5} {e.height + 1:>6} {POSE_NAMES[e.k]:>5} {' '.join(cells)}  {e.status}")
        missing = self.missing
        if missing:
            names = ", ".join(e.label for e in missing)
            lines.append(f"missing ({len(missing)} of {len(self.entries)}, not used): {names}")
        if self.suspects:
            lines.append("flagged, worst first:")
            lines += [f"  {s.label} [{s.field}]: {s.reason}" for s in self.suspects]
        if self.warnings:
            lines.append("warnings (the table passes):")
            lines += [f"  {s.label} [{s.field}]: {s.reason}" for s in self.warnings]
        lines += [f"note: {n}" for n in self.notes]
        lines.append(f"reference: {self.reference}; rms {self.rms_mm:.3f} mm over {self.points_used} contacts")
        lines += rule.describe()
        if self.problem:
            lines.append(f"the fit is not sound: {self.problem}")
        present = [e for e in self.entries if e.status != "missing"]
        ok = sum(e.status in ("ok", "warn", "unchecked") for e in present)
        verdict = "; the table fails: it cannot be audited as it is" if self.problem else ""
        lines.append(f"{ok}/{len(present)} entries pass ({len(self.warnings)} with a warning, "
                     f"{len(self.suspects)} flagged){verdict}")
        return "\n".join(lines)


def _cell(x: float, width: int, digits: int) -> str:
    return f"{'-':>{width}}" if math.isnan(x) else f"{x:>{width}.{digits}f}"


def _num(x: float) -> float | None:
    """A JSON number (rounded to 1e-6), or null for NaN."""
    return None if math.isnan(x) else round(float(x), 6)


def _vec(v: tuple[float, float, float]) -> list[float] | None:
    return None if any(math.isnan(x) for x in v) else [round(float(x), 7) for x in v]


def _tolerance(th: Thresholds) -> str:
    if not th.derived:
        return f"{float(th.mm)} mm / {float(th.deg)} deg"
    return f"{th.mm:.1f} mm / {th.deg:.1f} deg"


__all__ = [
    "STATUSES",
    "STRICT_DEG",
    "STRICT_MM",
    "AuditEntry",
    "AuditReport",
]
