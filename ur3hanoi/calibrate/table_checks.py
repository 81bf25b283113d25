"""The evidence about taught contacts that does not depend on where the towers stand (issue 37): the table is flat,
a grasp is tool down, towers are distinct.

Real stations put their towers where the bench allows: 12-105 mm (median 50 mm) from where the base calibration's
layout, moved and turned as a whole, puts them. So the base says nothing about where a tower stands; what it does
say holds on every station:

- **levels** (:func:`level_checks`): the blocks stand on one flat table, so every tower's origin (its height 1
  contact, or where its contacts put it) is at one height: each tower within :data:`CONTACT_FLAG_MM` (8 mm) of the
  other towers' median. A contact is pressed onto its block until the cup touches: its height is set by the block,
  not by the student's eye, and scatters by about a millimetre, while a slot one height off, the home pose or a
  joint-2/3/4 offset moves it by centimetres.
- **the tool's axis** (:func:`tilt_checks`): a contact's suction axis within :data:`TILT_FLAG_DEG` (5 deg) of the
  other contacts of its tower; a tower's axis (all its contacts alike: how the student held the wrist there, up to
  6.3 deg on real stations) within :data:`TOWER_TILT_DEG` (8 deg) of the nearest other tower's. A point tilted
  from the
  others of its tower is wrong; a whole tower tilted alike is the tower's.
- **distinct towers** (:func:`distinct_checks`): two towers' origins at least one block edge apart horizontally
  (closer, their blocks would overlap: a pose recorded for the wrong tower, or copied).

What none of this sees: a tower taught at one pose may stand anywhere on the table; a joint-1 offset of its pose
moves it along the table with nothing else changed. The calibration says so (:func:`single_pose_towers`) instead of
refusing it.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.grid_fit import BoolArray
from ur3hanoi.calibrate.limits import CONTACT_FLAG_MM, TILT_FLAG_DEG, angle_deg

TOWER_TILT_DEG = 8.0
"""[deg] a tower whose every contact is tilted alike stands tilted (the student's wrist, a block set askew): its
axis may be this far from the other towers' (real stations: up to 6.3 deg)."""


def _unit(v: FloatArray) -> FloatArray:
    n = float(np.linalg.norm(v))
    return np.asarray(v / n if n > 0 else np.array([0.0, 0.0, -1.0]), dtype=float)


def level_checks(origins_m: FloatArray, judged: Sequence[int]) -> list[tuple[int, float]]:
    """Each ``judged`` tower's origin height [mm] from the median of the other judged towers' (``origins_m`` (T, 3)
    [m], NaN rows: no contact; a tower not judged, vouched for, is no reference either): (tower, signed difference
    [mm], positive: higher)."""
    present = [t for t in judged if not np.isnan(origins_m[t, 0])]
    out = []
    for t in judged:
        others = [o for o in present if o != t]
        if t in present and others:
            out.append((t, float(origins_m[t, 2] - np.median(origins_m[others, 2])) * 1e3))
    return out


def tilt_checks(axes: FloatArray, towers: Sequence[int]) -> tuple[list[tuple[int, float]], list[tuple[int, float]]]:
    """The tool's axis of contacts ``axes`` (N, 3) on ``towers`` (N,): (point, deg from the other contacts of its
    tower) for points with such mates; (tower, deg of its mean axis from the nearest other tower's) for every tower
    with another beside it."""
    axes = np.asarray(axes, dtype=float).reshape(-1, 3)
    tw = np.asarray(towers, dtype=int)
    points, lean = [], []
    for j in range(len(axes)):
        mates = (tw == tw[j]) & (np.arange(len(axes)) != j)
        if mates.any():
            points.append((j, float(angle_deg(axes[j:j + 1], _unit(axes[mates].mean(axis=0)))[0])))
    own = {t: _unit(axes[tw == t].mean(axis=0)) for t in sorted(set(tw.tolist()))}
    for t, a in own.items():  # from the nearest other tower: one tilted tower does not make a third one lean
        others = [b for u, b in own.items() if u != t]
        if others:
            lean.append((t, float(np.min(angle_deg(np.array(others), a)))))
    return points, lean


def distinct_checks(origins_m: FloatArray, block_m: float) -> list[tuple[int, int, float]]:
    """Every pair of towers with an origin: (tower a, tower b, horizontal distance [mm]); they are distinct when
    at least a block edge (``block_m``) apart."""
    present = [t for t in range(len(origins_m)) if not np.isnan(origins_m[t, 0])]
    return [(a, b, float(np.hypot(*(origins_m[a, :2] - origins_m[b, :2]))) * 1e3)
            for i, a in enumerate(present) for b in present[i + 1:]]


def share(value: float, limit: float) -> float:
    """``value`` over ``limit`` (over 1: disagrees)."""
    return abs(value) / limit


def single_pose_towers(slots: Sequence[tuple[int, int, int]], used: Sequence[bool] | BoolArray) -> dict[int, int]:
    """The towers whose place rests on one pose of the points ``used``: tower -> the index of that pose (a contact:
    an above pose alone does not place a tower). A second contact or an above pose over its tower checks it."""
    per: dict[int, list[int]] = {}
    for i, (t, _, _) in enumerate(slots):
        if used[i]:
            per.setdefault(t, []).append(i)
    return {t: idx[0] for t, idx in per.items() if len(idx) == 1 and slots[idx[0]][2] == 0}


__all__ = ["CONTACT_FLAG_MM", "TILT_FLAG_DEG", "TOWER_TILT_DEG", "distinct_checks", "level_checks", "share",
           "single_pose_towers", "tilt_checks"]
