"""The rule a hand-recorded table is audited by, in mm and deg (``check-table --fit``).

A **contact** ("on") entry is judged by where its suction point is against the grid fitted to the table's other
contacts (horizontally off its tower's vertical line, vertically off its level's height) and by its suction axis
against the table's own axis (:func:`table_axis`); its heading about the suction axis (wrist 3, the direction the
arm arrives from) is never judged: a round cup on a cube does not care.

- never flagged: within :data:`CONTACT_OK_MM` (5 mm) of the line and of the level, axis within
  :data:`TILT_OK_DEG` (4 deg) of the table's;
- always flagged: the suction point more than :data:`CONTACT_FLAG_MM` (8 mm) from where the grid puts it (in all;
  within 5 mm of both the line and the level is at most 7.1 mm), or the axis more than :data:`TILT_FLAG_DEG`
  (5 deg) from the table's;
- in between a warning when off the line or the level (or the axis) by more than the data's own threshold,
  ``WARN_SIGMAS`` (5) robust sigmas of this table's contacts clamped to [5, 8] mm and [4, 5] deg; the table
  passes.

The numbers' one home is :mod:`ur3hanoi.calibrate.limits` (a calibration decides which taught point is wrong by
the same ones): recording noise on a hand-jogged UR3 is 1-3 mm, a suction cup seals within a few degrees, so the
data may add warnings, never rejections inside these floors.

An **above** entry is judged against its contact's fitted vertical line and the table's top level (the highest
fitted contact level over all towers: a carried block must clear a full stack):

- accepted: at least :data:`ABOVE_CLEAR_MM` (10 mm) over the top level and within :data:`ABOVE_LINE_MM` (8 mm) of
  the line;
- flagged: less than :data:`ABOVE_MIN_MM` (5 mm) over the top level or over its own contact level, or more than
  :data:`ABOVE_FLAG_LINE_MM` (10 mm) off the line;
- in between a warning. Its tilt is reported, never judged (nothing touches there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.limits import (
    ABOVE_CLEAR_MM,
    ABOVE_FLAG_LINE_MM,
    ABOVE_LINE_MM,
    ABOVE_MIN_MM,
    CONTACT_FLAG_MM,
    CONTACT_OK_MM,
    TILT_FLAG_DEG,
    TILT_OK_DEG,
    angle_deg,
    table_axis,
)

WARN_SIGMAS = 5.0
"""Warnings start this many robust sigmas of the table's own scatter out (clamped to the floors and ceilings)."""
MIN_CONTACTS_FOR_SCALE = 6
"""Fewer checkable contacts than this give no scatter estimate: warnings start at the floors."""
SIGMA_FLOOR_MM = 0.1
"""[mm] no table scatters less than a real UR3 repeats (about 0.1 mm): the smallest scatter an audit assumes."""
SIGMA_FLOOR_DEG = 0.05
"""[deg] the smallest scatter of the suction axes an audit assumes."""
MAXWELL_MEDIAN = 1.5382
"""Median length of a 3-D standard normal vector: per-axis sigma = median distance / 1.538."""
RAYLEIGH_MEDIAN = 1.1774
"""Median length of a 2-D standard normal vector: the sigma of a tilt = median tilt / 1.177."""

STATUSES: tuple[str, ...] = ("ok", "warn", "flagged", "unchecked")


@dataclass(frozen=True)
class AuditRule:
    """Every threshold one audit used.

    Attributes:
        warn_mm: a contact further than this off its line or its level gets a warning [mm], in [5, 8].
        flag_mm: a contact further than this from where the grid puts it (in all) is flagged [mm] (8, or a fixed
            tolerance).
        warn_deg: a contact's axis further than this from the table's gets a warning [deg], in [4, 5].
        flag_deg: ... is flagged [deg] (5, or a fixed tolerance).
        sigma_mm: robust scatter of the contacts per axis [mm], at least :data:`SIGMA_FLOOR_MM` (NaN: too few to
            estimate).
        sigma_deg: robust scatter of the contacts' axes [deg], at least :data:`SIGMA_FLOOR_DEG` (NaN: too few).
        fixed: True when ``flag_mm`` / ``flag_deg`` were given (``--tol-mm`` / ``--tol-deg``).
    """

    warn_mm: float
    flag_mm: float
    warn_deg: float
    flag_deg: float
    sigma_mm: float
    sigma_deg: float
    fixed: bool = False

    def to_json(self) -> dict[str, Any]:
        """Every threshold, named by what it is for (``--json``'s ``"rule"``)."""
        def num(x: float) -> float | None:
            return None if math.isnan(x) else round(float(x), 6)

        return {
            "contact": {"never_flagged_within_mm": CONTACT_OK_MM, "never_flagged_within_deg": TILT_OK_DEG,
                        "warn_over_mm": num(self.warn_mm), "warn_over_deg": num(self.warn_deg),
                        "flagged_over_mm": num(self.flag_mm), "flagged_over_deg": num(self.flag_deg)},
            "above": {"accepted_over_top_mm": ABOVE_CLEAR_MM, "accepted_within_line_mm": ABOVE_LINE_MM,
                      "flagged_under_top_or_contact_mm": ABOVE_MIN_MM, "flagged_off_line_mm": ABOVE_FLAG_LINE_MM,
                      "tilt_judged": False},
            "heading_judged": False,
            "warn_sigmas": WARN_SIGMAS,
            "sigma_mm": num(self.sigma_mm),
            "sigma_deg": num(self.sigma_deg),
            "fixed": self.fixed,
        }

    def describe(self) -> list[str]:
        """The rule in words, with this table's numbers (one line each)."""
        scatter = ("too few contacts to estimate this table's scatter: warnings start at the floors"
                   if math.isnan(self.sigma_mm) else
                   f"this table's contacts scatter {self.sigma_mm:.2f} mm per axis and {self.sigma_deg:.2f} deg "
                   f"(robust sigma): warnings from {WARN_SIGMAS:g} sigma, clamped to [{CONTACT_OK_MM:g}, "
                   f"{CONTACT_FLAG_MM:g}] mm / [{TILT_OK_DEG:g}, {TILT_FLAG_DEG:g}] deg")
        fixed = " (fixed by --tol-mm/--tol-deg)" if self.fixed else ""
        return [
            f"rule: a contact within {CONTACT_OK_MM:g} mm of its tower's line and its level, axis within "
            f"{TILT_OK_DEG:g} deg of the table's, is never flagged; more than {self.flag_mm:g} mm off in all or "
            f"{self.flag_deg:g} deg tilted is flagged{fixed}; a warning over {self.warn_mm:.1f} mm off the line or "
            f"level / {self.warn_deg:.1f} deg (the table passes); heading about the suction axis is not judged",
            f"rule: an above pose at least {ABOVE_CLEAR_MM:g} mm over the top level and within {ABOVE_LINE_MM:g} mm "
            f"of its contact's line is accepted; less than {ABOVE_MIN_MM:g} mm over the top level or its contact, "
            f"or more than {ABOVE_FLAG_LINE_MM:g} mm off the line, is flagged; its tilt is not judged",
            f"scatter: {scatter}",
        ]


def derive_rule(dev_mm: FloatArray, tilt_deg: FloatArray, tol_mm: float | None = None,
                tol_deg: float | None = None) -> AuditRule:
    """The rule for one table from its checkable contacts' 3-D deviations [mm] and tilts from the table's axis
    [deg]; ``tol_mm`` / ``tol_deg`` replace the flag thresholds (the warnings then start at most there)."""
    dev = np.asarray(dev_mm, dtype=float)
    dev = dev[np.isfinite(dev)]
    tilt = np.asarray(tilt_deg, dtype=float)
    tilt = tilt[np.isfinite(tilt)]
    s_mm = (max(float(np.median(dev)) / MAXWELL_MEDIAN, SIGMA_FLOOR_MM) if dev.size >= MIN_CONTACTS_FOR_SCALE
            else math.nan)
    s_deg = (max(float(np.median(tilt)) / RAYLEIGH_MEDIAN, SIGMA_FLOOR_DEG) if tilt.size >= MIN_CONTACTS_FOR_SCALE
             else math.nan)
    flag_mm = CONTACT_FLAG_MM if tol_mm is None else float(tol_mm)
    flag_deg = TILT_FLAG_DEG if tol_deg is None else float(tol_deg)
    warn_mm = CONTACT_OK_MM if math.isnan(s_mm) else min(max(WARN_SIGMAS * s_mm, CONTACT_OK_MM), CONTACT_FLAG_MM)
    warn_deg = TILT_OK_DEG if math.isnan(s_deg) else min(max(WARN_SIGMAS * s_deg, TILT_OK_DEG), TILT_FLAG_DEG)
    return AuditRule(warn_mm=min(warn_mm, flag_mm), flag_mm=flag_mm, warn_deg=min(warn_deg, flag_deg),
                     flag_deg=flag_deg, sigma_mm=s_mm, sigma_deg=s_deg,
                     fixed=tol_mm is not None or tol_deg is not None)


@dataclass(frozen=True)
class Verdict:
    """How one entry fares: ``status`` (one of :data:`STATUSES`), ``severity`` (how far past its flag threshold,
    1 = at it; flagged entries sort by it) and ``why`` (what is off and by how much, for people)."""

    status: str
    severity: float
    why: str


def _sigmas(x: float, sigma: float) -> str:
    return "" if math.isnan(sigma) or sigma <= 0 else f", {x / sigma:.0f} sigma of this table's scatter"


def judge_contact(off_line_mm: float, off_level_mm: float, tilt_deg: float, rule: AuditRule) -> Verdict:
    """A contact's verdict from its distance off its tower's line [mm], off its level (signed, + above) [mm] and
    its axis' angle from the table's [deg].

    Flagged when the suction point is more than ``flag_mm`` from where the grid puts it (the distance in all:
    a point within 5 mm of both the line and the level is at most 7.1 mm away) or the axis more than ``flag_deg``
    from the table's; warned when off the line or the level by more than ``warn_mm`` (at least 5 mm), or the axis
    by more than ``warn_deg`` (at least 4 deg)."""
    off = math.hypot(off_line_mm, off_level_mm)
    severity = max(off / rule.flag_mm, tilt_deg / rule.flag_deg)
    parts: list[str] = []
    status = "ok"
    where = (f"{off_line_mm:.1f} mm off its tower's line, {abs(off_level_mm):.1f} mm "
             f"{'above' if off_level_mm >= 0 else 'below'} its level")
    noise = (f"recording noise is 1-3 mm{_sigmas(off, rule.sigma_mm)}")
    if off > rule.flag_mm:
        status = "flagged"
        parts.append(f"{where}: more than {rule.flag_mm:g} mm in all ({noise})")
    elif max(off_line_mm, abs(off_level_mm)) > rule.warn_mm:
        status = "warn"
        parts.append(f"{where}: more than {rule.warn_mm:.1f} mm, within {rule.flag_mm:g} mm in all ({noise})")
    if tilt_deg > rule.flag_deg:
        status = "flagged"
        parts.append(f"its suction axis is {tilt_deg:.1f} deg from the table's: more than {rule.flag_deg:g} deg (a "
                     f"suction cup seals within a few degrees{_sigmas(tilt_deg, rule.sigma_deg)})")
    elif tilt_deg > rule.warn_deg:
        status = "warn" if status == "ok" else status
        parts.append(f"its suction axis is {tilt_deg:.1f} deg from the table's: more than {rule.warn_deg:.1f} deg, "
                     f"within {rule.flag_deg:g} deg")
    return Verdict(status=status, severity=severity, why="; ".join(parts))


def _over(mm: float) -> str:
    return f"only {mm:.1f} mm over" if mm >= 0 else f"{-mm:.1f} mm below"


def judge_above(off_line_mm: float, over_top_mm: float, over_contact_mm: float) -> Verdict:
    """An above pose's verdict from its distance off its contact's vertical line [mm] and its height over the
    table's top level and over its own contact level [mm] (tilt is not judged)."""
    low = min(over_top_mm, over_contact_mm)
    severity = max(off_line_mm / ABOVE_FLAG_LINE_MM, 1.0 + (ABOVE_MIN_MM - low) / ABOVE_MIN_MM)
    flags, warns = [], []
    if over_top_mm < ABOVE_MIN_MM:
        flags.append(f"{_over(over_top_mm)} the table's top level (less than {ABOVE_MIN_MM:g} mm over it: a carried "
                     "block would hit a full stack)")
    elif over_top_mm < ABOVE_CLEAR_MM:
        warns.append(f"{over_top_mm:.1f} mm over the table's top level (less than {ABOVE_CLEAR_MM:g} mm)")
    if over_contact_mm < ABOVE_MIN_MM and over_contact_mm < over_top_mm:
        flags.append(f"{_over(over_contact_mm)} its own contact (less than {ABOVE_MIN_MM:g} mm over it)")
    if off_line_mm > ABOVE_FLAG_LINE_MM:
        flags.append(f"{off_line_mm:.1f} mm off its contact's vertical line (more than {ABOVE_FLAG_LINE_MM:g} mm)")
    elif off_line_mm > ABOVE_LINE_MM:
        warns.append(f"{off_line_mm:.1f} mm off its contact's vertical line (more than {ABOVE_LINE_MM:g} mm)")
    status = "flagged" if flags else "warn" if warns else "ok"
    return Verdict(status=status, severity=severity, why="; ".join(flags + warns))


__all__ = [
    "ABOVE_CLEAR_MM",
    "ABOVE_FLAG_LINE_MM",
    "ABOVE_LINE_MM",
    "ABOVE_MIN_MM",
    "CONTACT_FLAG_MM",
    "CONTACT_OK_MM",
    "SIGMA_FLOOR_DEG",
    "SIGMA_FLOOR_MM",
    "STATUSES",
    "TILT_FLAG_DEG",
    "TILT_OK_DEG",
    "WARN_SIGMAS",
    "AuditRule",
    "Verdict",
    "angle_deg",
    "derive_rule",
    "judge_above",
    "judge_contact",
    "table_axis",
]
