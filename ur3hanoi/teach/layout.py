"""Check taught contacts against the base calibration's layout, where the points alone cannot check them.

Three taught points, one per tower, determine the grid exactly: the fit has nothing left over to check them with
(the audit calls every one of them ``unchecked``), so a pose 15 mm off would go into the calibration unnoticed.
The base calibration knows more than the fit uses: how far apart its towers stand, the table they stand on, the
block size its levels step by. A real station is the base's layout put down about where the base says: moved a
few mm and turned a few degrees as a whole.

The model: the base's grid points of the taught slots, turned by ``theta`` about the vertical through their
centroid and shifted by ``s`` (x, y, z), fitted to the measured suction points by regularized least squares::

    cost = sum |p_i - (R(theta) (a_i - c) + c + s)|^2 / sigma^2 + (theta / TURN_PRIOR)^2 + |s|^2 / SHIFT_PRIOR^2

with ``sigma`` = :data:`SIGMA_MM` (a hand-taught pose scatters by 1-3 mm), :data:`TURN_PRIOR_DEG` and
:data:`SHIFT_PRIOR_MM` (how far a station usually stands from its calibration). Each point is compared with where
the fit of the *other* points puts it (leave one out): more than ``threshold_mm`` away, it disagrees with them.
Who is off? For each point over the threshold, the cost of the others' fit says how well the others agree with
each other and with the base once it is left out; the point whose removal leaves the cheapest fit is named, and
the others are then measured against that fit (their own leave-one-out distance would carry the named point's
error). With three points a pose off across the tower row bends the row wherever it is, and only the prior on the
turn and shift can tell which: the message then says the points alone cannot be sure (:data:`AMBIGUOUS_COST`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray

SIGMA_MM = 1.0
"""[mm] per-axis scatter of a taught pose the fit assumes."""
TURN_PRIOR_DEG = 3.0
"""[deg] how far a station's tower row is usually turned from its calibration's (one standard deviation)."""
SHIFT_PRIOR_MM = 10.0
"""[mm] how far a station's towers usually stand from where its calibration puts them (one standard deviation)."""
AMBIGUOUS_COST = 2.0
"""Another point whose removal leaves a fit cheaper than this over the best one's could be the odd one out too."""
_MAX_TURN_DEG = 45.0  # the turn is searched within +-this
_GRID_DEG = 1.0  # coarse search step before the golden-section refinement


def _rot_z(theta: float) -> FloatArray:
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass(frozen=True)
class LayoutFit:
    """The base's points turned by ``theta`` [rad] about the vertical through ``pivot`` (3,) [mm] and shifted by
    ``shift`` (3,) [mm]; ``cost`` is the regularized cost of the fit (see the module docstring)."""

    theta: float
    shift: FloatArray
    pivot: FloatArray
    cost: float

    def apply(self, a_mm: FloatArray) -> FloatArray:
        """Where the fit puts the base's points ``a_mm`` (N, 3) [mm]."""
        a = np.asarray(a_mm, dtype=float).reshape(-1, 3) - self.pivot
        return a @ _rot_z(self.theta).T + self.pivot + self.shift


def _cost(a: FloatArray, b: FloatArray, theta: float) -> tuple[float, FloatArray]:
    """The cost and the best shift at turn ``theta`` (``a``, ``b`` about the pivot, [mm])."""
    ra = a @ _rot_z(theta).T
    w = 1.0 / SIGMA_MM**2
    shift = w * (b - ra).sum(axis=0) / (len(a) * w + 1.0 / SHIFT_PRIOR_MM**2)
    r = b - ra - shift
    prior = (math.degrees(theta) / TURN_PRIOR_DEG) ** 2 + float(shift @ shift) / SHIFT_PRIOR_MM**2
    cost = w * float(np.sum(r * r)) + prior
    return cost, shift


def fit_layout(a_mm: FloatArray, b_mm: FloatArray, pivot_mm: FloatArray) -> LayoutFit:
    """The regularized fit of the base's points ``a_mm`` (N, 3) to the measured ``b_mm`` (N, 3) [mm], turning about
    ``pivot_mm``: a coarse search of the turn, then golden-section refinement."""
    pivot = np.asarray(pivot_mm, dtype=float)
    a = np.asarray(a_mm, dtype=float).reshape(-1, 3) - pivot
    b = np.asarray(b_mm, dtype=float).reshape(-1, 3) - pivot
    grid = np.radians(np.arange(-_MAX_TURN_DEG, _MAX_TURN_DEG + 1e-9, _GRID_DEG))
    costs = [_cost(a, b, t)[0] for t in grid]
    i = int(np.argmin(costs))
    lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, len(grid) - 1)])
    g = (math.sqrt(5.0) - 1.0) / 2.0
    for _ in range(40):
        m1, m2 = hi - g * (hi - lo), lo + g * (hi - lo)
        if _cost(a, b, m1)[0] < _cost(a, b, m2)[0]:
            hi = m2
        else:
            lo = m1
    theta = 0.5 * (lo + hi)
    cost, shift = _cost(a, b, theta)
    return LayoutFit(theta=theta, shift=shift, pivot=pivot, cost=cost)


@dataclass(frozen=True)
class LayoutCheck:
    """Every contact against the base's layout fitted to the others.

    Attributes:
        deviation_mm: per point, its distance [mm] from where the layout fitted to the other points puts it (NaN
            for a single point); with a point named, the others' distance from the fit without it.
        suspects: the points named (indices; at most one).
        ambiguous: True when another point over the threshold could be the odd one out as well.
        theta_deg: the turn of the base's layout fitted to the points (all but the one named) [deg].
        shift_mm: its shift (3,) [mm].
    """

    deviation_mm: FloatArray
    suspects: tuple[int, ...]
    ambiguous: bool
    theta_deg: float
    shift_mm: FloatArray


def check_layout(base_mm: Sequence[Sequence[float]] | FloatArray, measured_mm: Sequence[Sequence[float]] | FloatArray,
                 pivot_mm: Sequence[float] | FloatArray, threshold_mm: float) -> LayoutCheck:
    """Judge the measured contacts ``measured_mm`` (N, 3) against the base calibration's grid points of the same
    slots ``base_mm`` (N, 3), turning about ``pivot_mm`` (the centroid of the base's tower origins) [mm, world]
    (see the module docstring)."""
    a = np.asarray(base_mm, dtype=float).reshape(-1, 3)
    b = np.asarray(measured_mm, dtype=float).reshape(-1, 3)
    pivot = np.asarray(pivot_mm, dtype=float)
    n = len(a)
    dev = np.full(n, np.nan)
    cost = np.full(n, np.inf)
    for i in range(n if n > 1 else 0):
        others = [j for j in range(n) if j != i]
        fit = fit_layout(a[others], b[others], pivot)
        dev[i] = float(np.linalg.norm(b[i] - fit.apply(a[i])[0]))
        cost[i] = fit.cost
    whole = fit_layout(a, b, pivot) if n else LayoutFit(0.0, np.zeros(3), pivot, 0.0)
    over = np.flatnonzero(np.nan_to_num(dev, nan=0.0) > threshold_mm)
    suspects: tuple[int, ...] = ()
    ambiguous = False
    if over.size:
        best = int(over[np.argmin(cost[over])])
        suspects = (best,)
        ambiguous = bool(np.sum(cost[over] < cost[best] + AMBIGUOUS_COST) > 1)
        others = [j for j in range(n) if j != best]
        whole = fit_layout(a[others], b[others], pivot)
        dev[others] = np.linalg.norm(b[others] - whole.apply(a[others]), axis=1)
    return LayoutCheck(deviation_mm=dev, suspects=suspects, ambiguous=ambiguous,
                       theta_deg=math.degrees(whole.theta), shift_mm=whole.shift)


__all__ = ["AMBIGUOUS_COST", "SHIFT_PRIOR_MM", "SIGMA_MM", "TURN_PRIOR_DEG", "LayoutCheck", "LayoutFit",
           "check_layout", "fit_layout"]
