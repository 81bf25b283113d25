"""The limits, in mm and deg, past which a taught pose or a table entry is wrong: the audit's rule and the
calibration's choice of which point is wrong share them (their one home; :mod:`ur3hanoi.audit.rule` says how the
audit applies them, :mod:`ur3hanoi.calibrate.consensus` how a calibration does).

Recording noise on a hand-jogged UR3 is 1-3 mm (the arm itself repeats to about 0.1 mm); a suction cup seals within
a few degrees. Inside the "never flagged" limits nothing is ever called wrong; past the "always flagged" ones a
pose disagrees with the others, whatever the data's own scatter.

The suction axis of a table (or of a set of taught poses) is its own (:func:`table_axis`), not straight down: a
robot base or tool mount a little off level tilts every pose alike.
"""

from __future__ import annotations

import numpy as np

from ur3hanoi.arrays import FloatArray

CONTACT_OK_MM = 5.0
"""[mm] a contact this close to its tower's line and its level's height is never flagged."""
CONTACT_FLAG_MM = 8.0
"""[mm] a contact whose suction point is farther than this from where the grid puts it is always flagged."""
TILT_OK_DEG = 4.0
"""[deg] a suction axis this close to the table's is never flagged."""
TILT_FLAG_DEG = 5.0
"""[deg] a contact's suction axis farther than this from the table's is always flagged."""
ABOVE_CLEAR_MM = 10.0
"""[mm] an above pose at least this far over the table's top level (and on its line) is accepted."""
ABOVE_LINE_MM = 8.0
"""[mm] an above pose within this of its contact's vertical line (and clear of the top) is accepted."""
ABOVE_MIN_MM = 5.0
"""[mm] an above pose less than this over the table's top level or its own contact is flagged."""
ABOVE_FLAG_LINE_MM = 10.0
"""[mm] an above pose farther than this from its contact's vertical line is flagged."""
MAX_APPROACH_M = 0.5
"""[m] the largest approach height (an above pose over its contact) a calibration may have."""


def angle_deg(a: FloatArray, b: FloatArray) -> FloatArray:
    """Angle [deg] between unit vectors ``a`` (N, 3) and ``b`` (3,)."""
    return np.degrees(np.arccos(np.clip(np.asarray(a) @ np.asarray(b), -1.0, 1.0)))


def table_axis(axes: FloatArray) -> FloatArray:
    """The table's own suction axis (unit vector, world): the robust mean of the contacts' axes (N, 3).

    The component-wise median direction, then the mean of the axes within ``max(2 deg, 3 x their median angle)``
    of it (a tilted entry cannot drag it); straight down with fewer than three contacts.
    """
    axes = np.asarray(axes, dtype=float).reshape(-1, 3)
    down = np.array([0.0, 0.0, -1.0])
    if len(axes) < 3:
        return down
    a = np.median(axes, axis=0)
    a = a / np.linalg.norm(a)
    off = angle_deg(axes, a)
    near = off <= max(2.0, 3.0 * float(np.median(off)))
    if near.sum() >= 2:
        a = axes[near].mean(axis=0)
        a = a / np.linalg.norm(a)
    return np.asarray(a, dtype=float)


__all__ = [
    "ABOVE_CLEAR_MM",
    "ABOVE_FLAG_LINE_MM",
    "ABOVE_LINE_MM",
    "ABOVE_MIN_MM",
    "CONTACT_FLAG_MM",
    "CONTACT_OK_MM",
    "MAX_APPROACH_M",
    "TILT_FLAG_DEG",
    "TILT_OK_DEG",
    "angle_deg",
    "table_axis",
]
