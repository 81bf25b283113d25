"""Audit a lab table, or taught points: every entry against a reference, the flagged entries worst first, and why.

Two references:

- **a calibration** (:func:`check_against`, :mod:`~ur3hanoi.audit.calibration`): each entry's FK suction point and
  tool orientation against the station's intended pose, over fixed tolerances (by default :data:`STRICT_MM` /
  :data:`STRICT_DEG`, 1 mm / 0.5 deg): a generated table reproduces its grid to 1e-9 m.
- **the table itself** (:func:`audit_table`, :mod:`~ur3hanoi.audit.fitted`): the grid fitted robustly to the
  table's contacts, every entry judged by the rule of :mod:`ur3hanoi.audit.rule` (in mm and deg: within 5 mm
  / 4 deg never flagged, over 8 mm / 5 deg always; the heading about the suction axis never judged; above poses
  clear of the top level and on their contact's line).

The report (:class:`AuditReport`, :mod:`~ur3hanoi.audit.report`) lists every slot of the table (present or
missing) with its measured and fitted suction points, how far it is off and why. Calibrating from taught points
gives the same report (:func:`report_from_fit`).
"""

from __future__ import annotations

from ur3hanoi.audit.calibration import audit_taught, check_against, default_base, report_from_fit
from ur3hanoi.audit.fitted import audit_table
from ur3hanoi.audit.report import STATUSES, STRICT_DEG, STRICT_MM, AuditEntry, AuditReport

__all__ = [
    "STATUSES",
    "STRICT_DEG",
    "STRICT_MM",
    "AuditEntry",
    "AuditReport",
    "audit_table",
    "audit_taught",
    "check_against",
    "default_base",
    "report_from_fit",
]
