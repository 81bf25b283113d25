"""The base calibration's tower layout, moved and turned as a whole: where it puts a tower the points alone cannot
place.

A tower taught at one contact only is placed by that one pose: nothing among the points checks it (the audit calls
it ``unchecked``), so a pose 15 mm off, or the home pose recorded in its slot, would move the tower unnoticed. The
base calibration knows more than the fit uses: how far apart its towers stand, the table they stand on. A real
station is the base's layout put down about where the base says: moved a few mm and turned a few degrees as a
whole. So a tower is judged against the layout fitted to the *other* towers (:func:`tower_deviation`).

The layout fit (:func:`fit_layout`): the base's points ``a_i`` turned by ``theta`` about the vertical through a
pivot and shifted by ``s`` (x, y, z), fitted to the measured points ``b_i`` by regularized least squares::

    cost = sum |b_i - (R(theta) (a_i - c) + c + s)|^2 / sigma^2 + (theta / TURN_PRIOR)^2 + |s|^2 / SHIFT_PRIOR^2

with ``sigma`` = :data:`SIGMA_MM` (a hand-taught pose scatters by 1-3 mm), :data:`TURN_PRIOR_DEG` and
:data:`SHIFT_PRIOR_MM` (how far a station usually stands from its calibration). The best shift at a given turn is
linear in the points, so the cost is a function of the turn alone, ``K - P cos(theta) - Q sin(theta) +
(theta / TURN_PRIOR)^2``: a coarse search of the turn, then Newton's steps, in closed form.

With one other tower only the turn is not determined by the points: the judged tower may then be turned about the
other by up to :data:`TURN_PRIOR_DEG` (a pose off across the row by less than that turn cannot be told from a turned
station; one off along the row or in height always can).
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
_GRID = np.radians(np.arange(-45.0, 45.0 + 1e-9, 1.0))  # the coarse search of the turn, before Newton's steps


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


def _terms(a: FloatArray, b: FloatArray) -> tuple[float, float, float]:
    """(sum of b.b + a.a - 2 bz az, sum of bx ax + by ay, sum of by ax - bx ay): ``sum b . R(theta) a`` is
    ``bz az + cos(theta) * second + sin(theta) * third``."""
    const = float(np.sum(b * b) + np.sum(a * a) - 2.0 * np.sum(b[..., 2] * a[..., 2]))
    c = float(np.sum(b[..., 0] * a[..., 0] + b[..., 1] * a[..., 1]))
    s = float(np.sum(b[..., 1] * a[..., 0] - b[..., 0] * a[..., 1]))
    return const, c, s


def fit_layout(a_mm: FloatArray, b_mm: FloatArray, pivot_mm: FloatArray) -> LayoutFit:
    """The regularized fit of the base's points ``a_mm`` (N, 3) to the measured ``b_mm`` (N, 3) [mm], turning about
    ``pivot_mm`` (see the module docstring)."""
    pivot = np.asarray(pivot_mm, dtype=float)
    a = np.asarray(a_mm, dtype=float).reshape(-1, 3) - pivot
    b = np.asarray(b_mm, dtype=float).reshape(-1, 3) - pivot
    w, lam, n = 1.0 / SIGMA_MM**2, 1.0 / SHIFT_PRIOR_MM**2, len(a)
    k = w * w / (n * w + lam)
    k0, c, s = _terms(a, b)
    K0, C, S = _terms(a.sum(axis=0), b.sum(axis=0))
    const, p, q = w * k0 - k * K0, 2.0 * (w * c - k * C), 2.0 * (w * s - k * S)

    k2 = (180.0 / math.pi / TURN_PRIOR_DEG) ** 2

    def cost(theta: float) -> float:
        return const - p * math.cos(theta) - q * math.sin(theta) + k2 * theta * theta

    grid = _GRID
    i = int(np.argmin(-p * np.cos(grid) - q * np.sin(grid) + k2 * grid * grid))
    lo, hi = float(grid[max(i - 1, 0)]), float(grid[min(i + 1, len(grid) - 1)])
    theta = float(grid[i])
    for _ in range(8):  # Newton's steps on the cost's slope, kept inside the coarse minimum's bracket
        slope = p * math.sin(theta) - q * math.cos(theta) + 2.0 * k2 * theta
        curve = p * math.cos(theta) + q * math.sin(theta) + 2.0 * k2
        step = slope / curve if curve > 0.0 else 0.0
        theta = min(max(theta - step, lo), hi)
        if abs(step) < 1e-12:
            break
    shift = w * (b - a @ _rot_z(theta).T).sum(axis=0) / (n * w + lam)
    return LayoutFit(theta=theta, shift=shift, pivot=pivot, cost=max(cost(theta), 0.0))


def _one_other(base_d: FloatArray, fitted_d: FloatArray) -> FloatArray:
    """``base_d`` (the judged tower minus the other, [mm]) turned towards ``fitted_d`` by at most the turn prior."""
    turn = math.atan2(float(base_d[0] * fitted_d[1] - base_d[1] * fitted_d[0]),
                      float(base_d[0] * fitted_d[0] + base_d[1] * fitted_d[1]))
    limit = math.radians(TURN_PRIOR_DEG)
    return np.asarray(_rot_z(min(max(turn, -limit), limit)) @ base_d)


def tower_place(base_mm: FloatArray, fitted_mm: FloatArray, judged: int, others: Sequence[int],
                pivot_mm: FloatArray) -> FloatArray | None:
    """Where the base's layout, moved and turned as a whole onto the ``others`` towers' fitted places, puts tower
    ``judged`` [mm, world]; None with no other tower.

    ``base_mm`` (T, 3): the base's tower origins; ``fitted_mm`` (T, 3): the fitted ones (the rows of ``others``;
    with one other tower also the judged one's, to choose the turn); ``pivot_mm``: the centroid of the base's
    origins. With one other tower the turn is the one (within :data:`TURN_PRIOR_DEG`) that brings the judged tower
    closest (see the module docstring)."""
    base = np.asarray(base_mm, dtype=float).reshape(-1, 3)
    fitted = np.asarray(fitted_mm, dtype=float).reshape(-1, 3)
    others = list(others)
    if not others:
        return None
    if len(others) == 1:
        o = others[0]
        return fitted[o] + _one_other(base[judged] - base[o], fitted[judged] - fitted[o])
    fit = fit_layout(base[others], fitted[others], np.asarray(pivot_mm, dtype=float))
    return np.asarray(fit.apply(base[judged])[0])


__all__ = ["SHIFT_PRIOR_MM", "SIGMA_MM", "TURN_PRIOR_DEG", "LayoutFit", "fit_layout", "tower_place"]
