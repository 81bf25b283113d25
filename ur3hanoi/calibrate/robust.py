"""Robust grid fit: a high-breakdown start, then leave-one-out growing and pruning with thresholds from the data.

Hand-recorded poses scatter by a few mm; some may be grossly wrong (a typo in one joint, an entry copied into the
wrong slot, two slots swapped). A plain least-squares fit spreads such an error over the points that share its
unknowns: two swapped heights of one tower even reverse that tower's share of the common height step, and then
every point looks equally wrong. Here:

1. **Start** (FAST-LTS, Rousseeuw & Van Driessen 1999): :data:`N_SUBSETS` random elemental subsets (points drawn
   in a seeded random order, each kept when it adds to the rank, until the subset determines the grid) are
   fitted; each fit is refined by concentration steps (refit to the ``h`` points closest to it) and the fit with
   the smallest sum of the ``h`` smallest squared distances wins. Its ``h`` closest points start the fit. ``h =
   (N + p + 1) // 2`` with ``p`` the unknowns counted in points (``ceil(unknowns / 3)``), the usual LTS coverage:
   as long as at most ``N - h`` points are gross errors, the start is clean. The trimmed sum also counts, per
   tower, the squared distance of its origin from the towers' median along the height step: the towers' first
   slots line up (stacked: all stand on one table; flat: the first rows form one line). This only breaks ties that
   positions alone leave open (in a contact-only table, swapping the first and last heights of a tower fits as
   well as two wrong entries with the tower's origin moved by two steps); the final fit does not use it. The
   :data:`N_STARTS` best distinct trimmed fits each go through step 3, and the one the most points agree with is
   kept (ties: the better trimmed fit): a trimmed fit may keep one point of a tower only, and if that is the wrong
   one, fewer of the others come back to it.
2. **Scatter**: every point's deviation from the grid fitted to the *other* points of the fit is computed in
   closed form (:func:`ur3hanoi.calibrate.grid_fit.leave_one_out`), with its orientation error from the grid pose
   (tool pointing down at the circular-mean yaw of the points in the fit); a point outside the fit gets its
   deviation from the fit. The scatter is estimated robustly over all candidate points: ``sigma_mm = median |d| /
   1.538`` (the median length of a 3-D standard normal vector is 1.538; the median ignores the gross errors), and
   likewise ``sigma_deg`` from the orientation errors. The thresholds are

       threshold_mm  = max(MIN_SUSPECT_MM  = 3 mm,  SUSPECT_SIGMAS (5) * sigma_mm)
       threshold_deg = max(MIN_SUSPECT_DEG = 2 deg, SUSPECT_SIGMAS (5) * sigma_deg)

   (the floors alone with fewer than :data:`MIN_POINTS_FOR_SCALE` checkable points; fixed tolerances when the
   caller gives them). A point's severity is ``max(d / threshold_mm, rot / threshold_deg)``.
3. **Grow and prune**, one point at a time: a point outside the fit whose deviation from it is within the
   thresholds is taken in; otherwise the point of the fit with the largest severity over 1 is left out, if the
   others still determine the grid. Never more than ``(N - 1) // 2`` points are left out. The thresholds stay
   fixed while a fit grows and shrinks, so the steps converge: every start is grown under the thresholds of the
   best trimmed fit, and the winner once more under those of its own fit.

The deviation reported for a suspect is its distance from the grid fitted to all the others, so one gross error
never drags the fit or hides behind the points it shares unknowns with.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.calibrate.grid_fit import (
    BoolArray,
    GridModel,
    GridSolution,
    Measured,
    circular_mean,
    leave_one_out,
    rotation_error_deg,
    solve,
)
from ur3hanoi.station.calibration import Station
from ur3hanoi.tables import Slot

MIN_SUSPECT_MM = 3.0
"""[mm] a point closer than this to the fitted grid is never suspect (hand recordings scatter by a few mm)."""
MIN_SUSPECT_DEG = 2.0
"""[deg] a tool orientation closer than this to the grid pose is never suspect."""
SUSPECT_SIGMAS = 5.0
"""Thresholds are this many robust standard deviations (when above the floors)."""
MIN_POINTS_FOR_SCALE = 6
"""Fewer checkable points than this give no scale estimate: the floors are the thresholds."""
MAXWELL_MEDIAN = 1.5382
"""Median length of a 3-D standard normal vector (chi distribution, 3 degrees of freedom)."""
N_SUBSETS = 200
"""Random elemental subsets tried for the robust start (seeded: the same points always give the same fit)."""
N_STARTS = 5
"""Best distinct trimmed fits grown and pruned; the one most points agree with is kept."""
_C_STEPS = 2  # concentration steps per subset; the best subset is iterated to convergence
_SEED = 0


@dataclass(frozen=True)
class Thresholds:
    """Suspect thresholds and how they were obtained.

    Attributes:
        mm: position threshold [mm].
        deg: orientation threshold [deg].
        sigma_mm: robust scatter of the positions [mm] per axis (NaN when not estimated).
        sigma_deg: robust scatter of the orientations [deg] (NaN when not estimated).
        derived: True when taken from the data (floors and sigmas), False for fixed tolerances.
    """

    mm: float
    deg: float
    sigma_mm: float
    sigma_deg: float
    derived: bool

    def describe(self) -> str:
        """``"5.1 mm / 2.0 deg = max(3 mm, 5 sigma) / max(2 deg, 5 sigma), robust sigma 1.28 mm / 0.31 deg"``."""
        if not self.derived:
            return f"{self.mm:g} mm / {self.deg:g} deg (fixed)"
        head = f"{self.mm:.1f} mm / {self.deg:.1f} deg"
        if math.isnan(self.sigma_mm):
            return f"{head} (the floors: too few points to estimate the scatter from the data)"
        return (f"{head} = max({MIN_SUSPECT_MM:g} mm, {SUSPECT_SIGMAS:g} sigma) / max({MIN_SUSPECT_DEG:g} deg, "
                f"{SUSPECT_SIGMAS:g} sigma), robust sigma {self.sigma_mm:.2f} mm / {self.sigma_deg:.2f} deg")


def robust_sigma(lengths: FloatArray) -> float:
    """Per-axis standard deviation from the lengths of 3-D deviations (median / 1.538); NaN if too few."""
    lengths = lengths[np.isfinite(lengths)]
    if lengths.size < MIN_POINTS_FOR_SCALE:
        return math.nan
    return float(np.median(lengths)) / MAXWELL_MEDIAN


def thresholds(dev_mm: FloatArray, rot_deg: FloatArray, tol_mm: float | None = None,
               tol_deg: float | None = None, mm_range: tuple[float, float] | None = None) -> Thresholds:
    """Thresholds from the deviations [mm] and orientation errors [deg] of the points in a fit (see the module
    docstring); ``tol_mm`` / ``tol_deg`` given: used as they are. ``mm_range`` (floor, ceiling) [mm] replaces the
    position floor :data:`MIN_SUSPECT_MM` and caps the threshold."""
    s_mm, s_deg = robust_sigma(dev_mm), robust_sigma(rot_deg)
    lo, hi = mm_range if mm_range is not None else (MIN_SUSPECT_MM, math.inf)
    mm = tol_mm if tol_mm is not None else min(max(lo, 0.0 if math.isnan(s_mm) else SUSPECT_SIGMAS * s_mm), hi)
    deg = tol_deg if tol_deg is not None else max(MIN_SUSPECT_DEG,
                                                  0.0 if math.isnan(s_deg) else SUSPECT_SIGMAS * s_deg)
    return Thresholds(mm=mm, deg=deg, sigma_mm=s_mm, sigma_deg=s_deg, derived=tol_mm is None or tol_deg is None)


@dataclass(frozen=True)
class RobustFit:
    """Result of :func:`robust_fit` for N points (only the candidates take part in the fit).

    Attributes:
        solution: the grid fitted to the points in ``used``.
        yaw: tool yaw [rad], circular mean of the headings of the points in ``used``.
        used: shape (N,), the points of the final fit.
        removable: shape (N,), points the others can be checked without (False: the point alone determines
            some unknown, e.g. the only point of a tower).
        deviation: shape (N, 3) [m, world], each point minus the grid: from the final fit for a point left out,
            from the fit of the others (leave one out) for a point in the fit (its own residual if not removable).
        rot_deg: shape (N,), orientation error from the grid pose [deg].
        thresholds: the suspect thresholds.
    """

    solution: GridSolution
    yaw: float
    used: BoolArray
    removable: BoolArray
    deviation: FloatArray
    rot_deg: FloatArray
    thresholds: Thresholds

    @property
    def deviation_mm(self) -> FloatArray:
        return np.linalg.norm(self.deviation, axis=1) * 1e3

    @property
    def severity(self) -> FloatArray:
        """``max(deviation / threshold_mm, rot / threshold_deg)`` per point: over 1 is suspect."""
        return np.maximum(self.deviation_mm / self.thresholds.mm, self.rot_deg / self.thresholds.deg)


def _evaluate(base: Station, model: GridModel, slots: Sequence[Slot], m: Measured, used: BoolArray,
              candidates: BoolArray, tol_mm: float | None, tol_deg: float | None,
              frozen: Thresholds | None = None, angle_deg: FloatArray | None = None,
              mm_range: tuple[float, float] | None = None) -> RobustFit:
    idx = np.flatnonzero(used)
    used_slots = [slots[i] for i in idx]
    solution = solve(base, model, used_slots, m.p_world[idx])
    yaw = circular_mean(m.heading[idx])
    deviation = m.p_world - solution.points(slots)
    removable = np.zeros(len(slots), dtype=bool)
    loo, can = leave_one_out(model, used_slots, m.p_world[idx], solution)
    deviation[idx[can]] = loo[can]
    removable[idx] = can
    rot = rotation_error_deg(m.R_world, yaw) if angle_deg is None else angle_deg
    dev_mm = np.linalg.norm(deviation, axis=1) * 1e3
    # The scale comes from every candidate, in the fit or not: the points of the fit alone are the closest ones
    # (after the trimmed start) and would understate it; the median ignores the gross errors among the others.
    checkable = candidates & (removable | ~used)
    th = frozen or thresholds(dev_mm[checkable], rot[candidates], tol_mm, tol_deg, mm_range)
    return RobustFit(solution=solution, yaw=yaw, used=used.copy(), removable=removable, deviation=deviation,
                     rot_deg=rot, thresholds=th)


class _Lts:
    """Least trimmed squares on the candidate points (see the module docstring, step 1)."""

    def __init__(self, base: Station, model: GridModel, slots: Sequence[Slot], p_world: FloatArray) -> None:
        self.base, self.model, self.slots, self.p = base, model, list(slots), p_world
        self.A = model.design(slots)

    def rows(self, idx: Sequence[int] | np.ndarray) -> np.ndarray:
        idx = np.asarray(idx, dtype=int)
        return (3 * idx[:, None] + np.arange(3)).reshape(-1)

    def determined(self, idx: np.ndarray) -> bool:
        return int(np.linalg.matrix_rank(self.A[self.rows(idx)])) == self.model.n_unknowns

    def fit(self, idx: np.ndarray) -> GridSolution:
        return solve(self.base, self.model, [self.slots[i] for i in idx], self.p[idx], self.A[self.rows(idx)])

    def sq_dist(self, sol: GridSolution, idx: np.ndarray) -> FloatArray:
        return np.asarray(np.sum((self.p[idx] - sol.points([self.slots[i] for i in idx])) ** 2, axis=1))

    def elemental(self, order: np.ndarray) -> np.ndarray | None:
        """Points taken in ``order`` while they add to the rank, until the subset determines the grid (None if the
        candidates never do). The rank is followed with an orthonormal basis of the rows taken (Gram-Schmidt): the
        design holds 0, 1 and small integers, so a new row either adds a unit-size direction or none."""
        n_unknowns = self.model.n_unknowns
        basis = np.zeros((n_unknowns, n_unknowns))
        rank = 0
        chosen: list[int] = []
        for i in order:
            grew = False
            for row in self.A[3 * int(i):3 * int(i) + 3]:
                taken = basis[:rank]
                rest = row - (taken @ row) @ taken
                norm = math.sqrt(float(rest @ rest))
                if norm > 1e-9:
                    basis[rank] = rest / norm
                    rank += 1
                    grew = True
            if grew:
                chosen.append(int(i))
                if rank == n_unknowns:
                    return np.array(chosen)
        return None

    def objective(self, sol: GridSolution, d2: FloatArray, h: int) -> float:
        length = float(np.linalg.norm(sol.step))
        along = sol.origins @ (sol.step / length if length > 1e-6 else np.array([0.0, 0.0, 1.0]))
        return float(np.sum(np.sort(d2)[:h]) + np.sum((along - np.median(along)) ** 2))

    def concentrate(self, sol: GridSolution, cand: np.ndarray, h: int, steps: int
                    ) -> tuple[float, np.ndarray, GridSolution]:
        best: tuple[float, np.ndarray, GridSolution] | None = None
        for _ in range(steps):
            d2 = self.sq_dist(sol, cand)
            keep = np.sort(cand[np.argsort(d2, kind="stable")[:h]])
            objective = self.objective(sol, d2, h)
            if best is not None and (objective >= best[0] or np.array_equal(keep, best[1])):
                break
            best = (objective, keep, sol)
            if not self.determined(keep):
                break
            sol = self.fit(keep)
        d2 = self.sq_dist(sol, cand)
        keep = np.sort(cand[np.argsort(d2, kind="stable")[:h]])
        objective = self.objective(sol, d2, h)
        if best is None or objective < best[0]:
            best = (objective, keep, sol)
        return best

    def starts(self, cand: np.ndarray) -> list[np.ndarray]:
        """The :data:`N_STARTS` best distinct trimmed fits' ``h`` closest candidates (indices), best first."""
        n = len(cand)
        h = min(n, (n + math.ceil(self.model.n_unknowns / 3) + 1) // 2)
        if h == n:  # no point to trim: every subset's trimmed fit is the fit of them all
            return [cand]
        rng = np.random.default_rng(_SEED)
        found: dict[tuple[int, ...], tuple[float, GridSolution]] = {}
        tried: set[tuple[int, ...]] = set()
        for _ in range(N_SUBSETS):
            subset = self.elemental(cand[rng.permutation(n)])
            if subset is None:
                continue
            # The same subset (drawn in another order) gives the same trimmed fit: concentrate it once.
            drawn = tuple(sorted(int(i) for i in subset))
            if drawn in tried:
                continue
            tried.add(drawn)
            objective, keep, sol = self.concentrate(self.fit(subset), cand, h, _C_STEPS)
            key = tuple(int(i) for i in keep)
            if key not in found or objective < found[key][0]:
                found[key] = (objective, sol)
        best = sorted(found.items(), key=lambda item: item[1][0])[:N_STARTS]
        out: list[np.ndarray] = []
        for _, (_, sol) in best:
            keep = self.concentrate(sol, cand, h, 50)[1]
            if self.determined(keep) and not any(np.array_equal(keep, o) for o in out):
                out.append(keep)
        return out or [cand]


def robust_fit(base: Station, model: GridModel, slots: Sequence[Slot], m: Measured, candidates: BoolArray,
               tol_mm: float | None = None, tol_deg: float | None = None, angle_deg: FloatArray | None = None,
               mm_range: tuple[float, float] | None = None, prune: bool = True) -> RobustFit:
    """Fit ``model`` to the ``candidates`` among the points measured at ``slots``, leaving out gross errors
    (see the module docstring).

    ``candidates`` must determine ``model``. ``tol_mm`` / ``tol_deg`` replace the derived thresholds.
    ``angle_deg`` (N,) replaces the orientation error judged with each point (default: its angle from the grid
    pose, heading included); zeros judge positions only (the audit checks the suction axis on its own).
    ``mm_range`` (floor, ceiling) [mm] bounds the derived position threshold instead of the floor alone. With
    ``prune`` False every candidate stays in the fit (the points are known to agree: they are only judged).
    """
    cand = np.flatnonzero(candidates)
    if not prune:
        every = np.zeros(len(slots), dtype=bool)
        every[cand] = True
        return _evaluate(base, model, slots, m, every, candidates, tol_mm, tol_deg, None, angle_deg, mm_range)
    starts = _Lts(base, model, slots, m.p_world).starts(cand) if 3 * len(cand) > model.n_unknowns else [cand]

    def mask(idx: np.ndarray) -> BoolArray:
        used = np.zeros(len(slots), dtype=bool)
        used[idx] = True
        return used

    def evaluate(used: BoolArray) -> RobustFit:
        return _evaluate(base, model, slots, m, used, candidates, tol_mm, tol_deg, None, angle_deg, mm_range)

    # Every start is grown and pruned under the same thresholds (those of the best trimmed fit), so that "more
    # points agree" compares like with like; the winner is then refined with the thresholds of its own fit.
    # Thresholds stay fixed while a fit grows and shrinks: re-estimating them after every change could swing a
    # point in and out.
    frozen = evaluate(mask(starts[0])).thresholds
    best: RobustFit | None = None
    for start in starts:
        fit = _grow_and_prune(base, model, slots, m, mask(start), candidates, tol_mm, tol_deg, frozen, angle_deg)
        if best is None or int(fit.used.sum()) > int(best.used.sum()):
            best = fit  # on a tie the earlier start: the better trimmed fit
    assert best is not None
    frozen = evaluate(best.used).thresholds
    fit = _grow_and_prune(base, model, slots, m, best.used, candidates, tol_mm, tol_deg, frozen, angle_deg)
    return replace(evaluate(fit.used), thresholds=frozen)


def _grow_and_prune(base: Station, model: GridModel, slots: Sequence[Slot], m: Measured, used: BoolArray,
                    candidates: BoolArray, tol_mm: float | None, tol_deg: float | None, frozen: Thresholds,
                    angle_deg: FloatArray | None = None) -> RobustFit:
    """Step 3 of the module docstring, from the points ``used``, with the thresholds ``frozen``."""
    n_cand = int(candidates.sum())
    max_left_out = (n_cand - 1) // 2
    used = used.copy()
    fit = _evaluate(base, model, slots, m, used, candidates, tol_mm, tol_deg, frozen, angle_deg)
    for _ in range(4 * n_cand + 4):
        outside = np.where(candidates & ~used, fit.severity, np.inf)
        inside = np.where(used & fit.removable, fit.severity, -np.inf)
        take, drop = int(np.argmin(outside)), int(np.argmax(inside))
        if outside[take] <= 1.0:
            used[take] = True
        elif inside[drop] > 1.0 and int((candidates & ~used).sum()) < max_left_out:
            used[drop] = False
        else:
            break
        fit = _evaluate(base, model, slots, m, used, candidates, tol_mm, tol_deg, frozen, angle_deg)
    return fit


__all__ = [
    "MAXWELL_MEDIAN",
    "MIN_POINTS_FOR_SCALE",
    "MIN_SUSPECT_DEG",
    "MIN_SUSPECT_MM",
    "N_SUBSETS",
    "SUSPECT_SIGMAS",
    "RobustFit",
    "Thresholds",
    "robust_fit",
    "robust_sigma",
    "thresholds",
]
