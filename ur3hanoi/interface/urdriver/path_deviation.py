"""How closely the arm followed the plan, from the joint states a client received: :func:`path_deviation`.

The measure is geometric, the plan's corridor: for every executed joint state, the distance [m] of its suction point
(forward kinematics, :func:`ur3hanoi.plan.kinematics.tcp_positions_world`) from the plan's suction-point path, the
largest over the solve; and the same over the samples nearest a vertical leg (descend, lift, place, retreat), where
the plan keeps within ``PlanConfig.vertical_tol_m`` (2 mm) of the line. Being late along the path (the slider, a
robot slowing itself down) is no deviation; cutting a corner to catch up is. Each joint state is measured against
the stretch of the path its goal was sent for (:func:`stretch_windows`: a motion's own; during a dwell, the motions
on either side), so an arm astray is not excused by another part of the path that passes nearby (the solve's
transits and carries cross the same places many times).

The plan's path is its exact Ruckig motion sampled at :data:`DENSE_RATE_HZ` and joined by straight pieces (within
1 micrometre of the curve on the lab's plans, which peak near 0.7 m/s: 0.7 mm pieces). Each executed point's distance
to the polyline is exact: a k-d tree over the pieces' midpoints finds every piece that can be the closest (any within
the nearest midpoint's distance plus half the longest piece), and the point-to-piece distances decide.

Computed once, after the solve (a 3-block solve: ~0.2 s), never on the control path.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.urdriver.plan_goals import Stretch
from ur3hanoi.plan import DWELL_PHASES, VERTICAL_PHASES, Phase, Plan, sample, tcp_positions_world

DENSE_RATE_HZ = 1000.0
"""[Hz] The rate at which the plan's path is sampled for the measure (see the module docstring)."""
_MOVED_M = 1e-12  # [m] a piece shorter than this (the arm at rest in a dwell) is left out


@dataclass(frozen=True)
class PathDeviation:
    """How far the executed suction point strayed from the plan's path.

    Attributes:
        max_m: the largest distance [m] of an executed suction point from the plan's path.
        vertical_max_m: the same over the executed points nearest a vertical leg [m] (None: there were none).
        worst_phase: the plan's phase nearest the worst point (``CARRY``).
        worst_t_s: when the worst point was received [s from the first joint state measured].
        samples: joint states measured.
    """

    max_m: float
    vertical_max_m: float | None
    worst_phase: str
    worst_t_s: float
    samples: int

    def describe(self) -> str:
        """``followed the plan within 0.41 mm (vertical legs 0.12 mm)``."""
        vertical = "" if self.vertical_max_m is None else f" (vertical legs {1e3 * self.vertical_max_m:.2f} mm)"
        return f"followed the plan within {1e3 * self.max_m:.2f} mm{vertical}"

    def as_dict(self) -> dict[str, object]:
        """The figures for a JSON outcome (millimetres, 4 decimals)."""
        return {"path_deviation_mm": round(1e3 * self.max_m, 4),
                "vertical_path_deviation_mm": None if self.vertical_max_m is None else
                round(1e3 * self.vertical_max_m, 4),
                "path_deviation_phase": self.worst_phase, "path_deviation_at_s": round(self.worst_t_s, 3),
                "joint_states_measured": self.samples}


@dataclass(frozen=True)
class PlanPath:
    """The plan's suction-point path as straight pieces ``a[i] -> b[i]`` [m] (world frame) from plan time ``t_a[i]``
    to ``t_b[i]`` [s], each with the plan's phase and whether it belongs to a vertical leg."""

    a: FloatArray
    b: FloatArray
    t_a: FloatArray
    t_b: FloatArray
    phase: npt.NDArray[np.int_]
    vertical: npt.NDArray[np.bool_]

    def between(self, t0: float, t1: float) -> PlanPath:
        """The pieces within plan time ``[t0, t1]`` [s] (all of them when none is)."""
        keep = (self.t_a >= t0 - 1e-9) & (self.t_b <= t1 + 1e-9)
        if not keep.any():
            return self
        return PlanPath(self.a[keep], self.b[keep], self.t_a[keep], self.t_b[keep], self.phase[keep],
                        self.vertical[keep])


def plan_path(plan: Plan, rate_hz: float = DENSE_RATE_HZ) -> PlanPath:
    """The plan's path (see the module docstring); a plan without its segments uses its own samples."""
    tr = sample(plan.segments, rate_hz) if plan.segments else plan.trajectory
    p = tcp_positions_world(plan.station, tr.q)
    phase = np.asarray(tr.phase, dtype=int)
    moving = np.linalg.norm(np.diff(p, axis=0), axis=1) > _MOVED_M
    if not moving.any():
        moving[0] = True  # a plan that never moves: its one point
    k = np.flatnonzero(moving)
    vertical = np.isin(phase, [int(x) for x in VERTICAL_PHASES])
    dwell = np.isin(phase[k], [int(x) for x in DWELL_PHASES])
    return PlanPath(p[k], p[k + 1], tr.t[k], tr.t[k + 1], np.where(dwell, phase[k + 1], phase[k]),
                    vertical[k] | vertical[k + 1])


def stretch_windows(plan: Plan, stretches: Sequence[Stretch]) -> FloatArray:
    """(len(stretches), 2) The plan time [s] whose path each stretch's joint states are measured against: a motion's
    own; a dwell's (the arm at rest where one motion ends and the next begins) both motions'."""
    t = plan.trajectory.t
    out = np.empty((len(stretches), 2))
    for i, s in enumerate(stretches):
        first = stretches[i - 1] if s.kind != "motion" and i > 0 else s
        last = stretches[i + 1] if s.kind != "motion" and i + 1 < len(stretches) else s
        out[i] = t[first.k0], t[last.k1]
    return out


def _point_piece_distances(x: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """Distances [m] of points ``x`` (n, 3) from the pieces ``a -> b`` (n, 3), row by row."""
    ab = b - a
    u = np.clip(np.einsum("ij,ij->i", x - a, ab) / np.einsum("ij,ij->i", ab, ab), 0.0, 1.0)
    return np.linalg.norm(a + u[:, None] * ab - x, axis=1)


def _nearest(path: PlanPath, x: FloatArray) -> tuple[FloatArray, npt.NDArray[np.bool_], npt.NDArray[np.int_]]:
    """Each point's distance [m] from ``path``, whether a closest piece is vertical, and the closest one's phase."""
    from scipy.spatial import cKDTree

    half = 0.5 * float(np.max(np.linalg.norm(path.b - path.a, axis=1)))
    tree = cKDTree(0.5 * (path.a + path.b))
    nearest, _ = tree.query(x)
    balls = tree.query_ball_point(x, nearest + half + 1e-12)  # every piece that can be the closest
    counts = np.fromiter((len(b) for b in balls), dtype=np.intp, count=len(balls))
    piece = np.concatenate([np.asarray(b, dtype=np.intp) for b in balls])
    point = np.repeat(np.arange(len(x)), counts)
    d = _point_piece_distances(x[point], path.a[piece], path.b[piece])
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]])
    best = np.minimum.reduceat(d, starts)
    on_vertical = np.minimum.reduceat(np.where(path.vertical[piece], d, np.inf), starts) <= best
    closest = piece[np.lexsort((d, point))[starts]]
    return best, on_vertical, path.phase[closest]


def path_deviation(plan: Plan, t: FloatArray, q: FloatArray, windows_s: FloatArray | None = None,
                   rate_hz: float = DENSE_RATE_HZ) -> PathDeviation:
    """The executed joint states ``q`` (n, 6) [rad, controller order], received at ``t`` (n,) [s], against
    ``plan``'s path (see the module docstring): each against the piece of the plan between its ``windows_s`` (n, 2)
    plan times [s] (the goal it was received in: :func:`stretch_windows`), or the whole path (None).

    Raises:
        ValueError: no joint states.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 6)
    if len(q) == 0:
        raise ValueError("no joint states to measure the path with")
    path = plan_path(plan, rate_hz)
    x = tcp_positions_world(plan.station, q)
    best, vertical, phase = np.empty(len(x)), np.empty(len(x), dtype=bool), np.empty(len(x), dtype=int)
    if windows_s is None:
        best, vertical, phase = _nearest(path, x)
    else:
        spans, which = np.unique(np.asarray(windows_s, dtype=float).reshape(-1, 2), axis=0, return_inverse=True)
        for j, (t0, t1) in enumerate(spans):
            idx = np.flatnonzero(which.ravel() == j)
            best[idx], vertical[idx], phase[idx] = _nearest(path.between(t0, t1), x[idx])
    worst = int(np.argmax(best))
    t = np.asarray(t, dtype=float)
    return PathDeviation(
        max_m=float(best[worst]),
        vertical_max_m=float(best[vertical].max()) if vertical.any() else None,
        worst_phase=Phase(int(phase[worst])).name,
        worst_t_s=float(t[worst] - t[0]),
        samples=len(q))
