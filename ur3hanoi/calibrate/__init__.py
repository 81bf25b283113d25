"""Calibrate a station's tower grid from taught poses (joint angles recorded on the teach pendant), robustly.

Workflow::

    ur3hanoi calibrate --taught my_taught.yaml --base lab_real -o my_station.yaml
    ur3hanoi tables my_station.yaml --key real_pos -o lab2_data.yaml

or, from an existing (e.g. hand-recorded) lab-format table, every entry ``Q[t][h][k]`` present used as a taught
point::

    ur3hanoi calibrate --from-table lab2_data.yaml --key real_pos --base lab_real -o out.yaml

The same robust fit, on a table's contacts alone, audits a table on its own (``ur3hanoi check-table --fit``,
:mod:`ur3hanoi.audit.fitted`), judging every entry by the audit's rule (:mod:`ur3hanoi.audit.rule`).

Module map:

- :mod:`~ur3hanoi.calibrate.grid_fit`: the grid as a linear model of FK suction points (``o_t + h s [+ a z]``), its
  least-squares solve and closed-form leave-one-out deviations.
- :mod:`~ur3hanoi.calibrate.limits`: the limits in mm and deg past which a pose is wrong (the audit's rule shares
  them).
- :mod:`~ur3hanoi.calibrate.layout`: the base calibration's tower layout moved and turned as a whole, where it puts
  a tower the points alone cannot place.
- :mod:`~ur3hanoi.calibrate.evidence`: a set of points judged on all the evidence (positions, the tool's
  orientation, the step and block size, the approach, the base's layout moved and turned as a whole).
- :mod:`~ur3hanoi.calibrate.consensus`: which point is grossly wrong, by what explains the most: the one whose
  removal leaves the others consistent; or that the points cannot tell.
- :mod:`~ur3hanoi.calibrate.robust`: sequential leave-one-out deletion of gross errors, with suspect thresholds
  from the data's robust scatter (``max(3 mm, 5 sigma)``, ``max(2 deg, 5 sigma)``).
- :mod:`~ur3hanoi.calibrate.explain`: why a pose is off (a typo in one joint, swapped or copied entries, a pose
  recorded in the wrong slot); :func:`~ur3hanoi.calibrate.explain.diagnose_contacts` with the heading left free.
- :mod:`~ur3hanoi.calibrate.verdict`: what a student reads about the point the consensus named (the arm at home,
  the wrong slot, a typo in one joint, not on the block) and what to do.
- :mod:`~ur3hanoi.calibrate.prepare`: the points a fit starts from: measured, the unusable set aside, the consensus
  on the rest (also what teach shows after each record, :func:`~ur3hanoi.calibrate.prepare.taught_consensus`).
- :mod:`~ur3hanoi.calibrate.fit`: :func:`fit_station`, the fit and the judgement of every point.
- :mod:`~ur3hanoi.calibrate.result`: its result, :class:`CalibrationFit`, and :class:`Suspect` (also the audit's).
- :mod:`~ur3hanoi.calibrate.output`: the calibration file written (refused when the fit is not sound).

What is fitted: one origin ``o_t`` per tower (explicit ``tower_origins``: real towers are rarely evenly spaced),
one height step ``s`` shared by all towers (when the points determine it; otherwise one block along world +z for
a stacked base, the base's step turned with the fitted tower row for a flat one), one approach height ``a`` (when
above poses are used), and the tool yaw (circular mean of the TCP headings). Everything else (robot base, TCP
offset, block size, contact depth, home, joint limits, counts, layout) is copied from the base calibration.

The taught-points file and its checks are :mod:`ur3hanoi.calibrate.taught`.
"""

from __future__ import annotations

from ur3hanoi.calibrate.explain import JOINT_LABELS, JointTypo, joint_typo
from ur3hanoi.calibrate.fit import fit_station
from ur3hanoi.calibrate.output import calibration_text, write_calibration
from ur3hanoi.calibrate.prepare import MAX_TILT_DEG
from ur3hanoi.calibrate.result import CalibrationFit, ResidualRow, Suspect
from ur3hanoi.calibrate.robust import (
    MIN_SUSPECT_DEG,
    MIN_SUSPECT_MM,
    SUSPECT_SIGMAS,
    Thresholds,
)

__all__ = [
    "JOINT_LABELS",
    "MAX_TILT_DEG",
    "MIN_SUSPECT_DEG",
    "MIN_SUSPECT_MM",
    "SUSPECT_SIGMAS",
    "CalibrationFit",
    "JointTypo",
    "ResidualRow",
    "Suspect",
    "Thresholds",
    "calibration_text",
    "fit_station",
    "joint_typo",
    "write_calibration",
]
