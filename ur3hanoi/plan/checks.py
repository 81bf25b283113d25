"""Safety checks of a sampled plan: joint limits (position, velocity, acceleration, jerk) and the vertical line.

Both return human-readable violations (empty: the check passed); :func:`ur3hanoi.plan.plan_moves` collects them.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.grid import contact_point_world
from ur3hanoi.hanoi import Move
from ur3hanoi.plan.types import VERTICAL_PHASES, KinematicLimits, Phase, Segment, Trajectory
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station

LIMIT_RTOL = 1e-6  # relative tolerance of the velocity/acceleration/jerk checks
POSITION_ATOL = 1e-9  # [rad] slack of the joint position limit check


def check_limits(tr: Trajectory, segments: Sequence[Segment], limits: KinematicLimits,
                 q_min: Sequence[float], q_max: Sequence[float]) -> list[str]:
    """Joint position (between samples too: Ruckig's position extrema, or the vertical path's nodes), velocity,
    acceleration and jerk limits at every sample (relative tolerance LIMIT_RTOL)."""
    out: list[str] = []
    lo, hi = np.asarray(q_min), np.asarray(q_max)
    for seg in segments:
        if seg.trajectory is None:
            continue
        if seg.path is not None:
            mins, maxs = seg.path.q.min(axis=0), seg.path.q.max(axis=0)
        else:
            mins = np.array([e.min for e in seg.trajectory.position_extrema])
            maxs = np.array([e.max for e in seg.trajectory.position_extrema])
        bad = np.flatnonzero((mins < lo - POSITION_ATOL) | (maxs > hi + POSITION_ATOL))
        for i in bad:
            out.append(f"joint {i + 1} position [{mins[i]:.4f}, {maxs[i]:.4f}] rad leaves [{lo[i]:.4f}, "
                       f"{hi[i]:.4f}] in {seg.phase.name} (move {seg.move_index + 1})")
    bad_q = (tr.q < lo - POSITION_ATOL) | (tr.q > hi + POSITION_ATOL)
    if np.any(bad_q):
        k, i = np.argwhere(bad_q)[0]
        out.append(f"joint {i + 1} position {tr.q[k, i]:.4f} rad outside limits at t = {tr.t[k]:.3f} s")
    for name, arr, lim in (("velocity", tr.qd, limits.v_max), ("acceleration", tr.qdd, limits.a_max),
                           ("jerk", tr.qddd, limits.j_max)):
        ratio = np.abs(arr) / lim
        if np.any(ratio > 1.0 + LIMIT_RTOL):
            k, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
            out.append(f"joint {i + 1} {name} {arr[k, i]:.6g} exceeds the limit {lim[i]:.6g} at t = "
                       f"{tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name})")
    return out


@lru_cache(maxsize=32)
def _tcp_frames(station: Station) -> tuple[tuple[float, float, float], FloatArray, FloatArray]:
    """The suction point in the flange frame (tool0) [m], and the world rotation and translation of ``base``."""
    t = load_ur3(station.tool, station.limits, station.robot).T_flange_tcp("tool0").translation
    T_wb = station.T_world_base
    return (float(t[0]), float(t[1]), float(t[2])), T_wb.rotation.copy(), T_wb.translation.copy()


def tcp_positions_world(station: Station, q: FloatArray) -> FloatArray:
    """World position [m] of the suction point at every row of ``q`` (N, 6): the UR3's DH forward kinematics in
    closed form (the chain of ``dh_fk`` multiplied out: joints 2-4 are parallel, so they add up to planar angles).

    Same kinematics as ``Ur3Model.fk(q, "tcp")`` (the URDF and the DH table agree to ~1e-11 m), without a
    per-sample Pinocchio call, and several times cheaper than the batched 4x4 products of ``dh_fk``: the vertical
    line of every leg is checked with it at 1 kHz.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 6)
    (tx, ty, tz), R_wb, p_wb = _tcp_frames(station)
    d1, _, _, d4, d5, d6 = station.robot.dh.d
    a2, a3 = station.robot.dh.a[1], station.robot.dh.a[2]
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    q23 = q[:, 1] + q[:, 2]
    q234 = q23 + q[:, 3]
    c234, s234 = np.cos(q234), np.sin(q234)
    c5, s5 = np.cos(q[:, 4]), np.sin(q[:, 4])
    c6, s6 = np.cos(q[:, 5]), np.sin(q[:, 5])
    # Frame 1 (after joint 1 and its alpha = pi/2): joints 2-4 rotate about its z axis. Tool offset rotated by
    # Rz(q234) Ry(-q5) Rz(q6).
    wx, wy = c6 * tx - s6 * ty, s6 * tx + c6 * ty
    ux, uz = c5 * wx - s5 * tz, s5 * wx + c5 * tz
    x = a2 * np.cos(q[:, 1]) + a3 * np.cos(q23) + d5 * s234 - d6 * s5 * c234 + c234 * ux - s234 * wy
    y = a2 * np.sin(q[:, 1]) + a3 * np.sin(q23) - d5 * c234 - d6 * s5 * s234 + s234 * ux + c234 * wy
    z = d4 + d6 * c5 + uz
    p_base = np.stack([c1 * x + s1 * z, s1 * x - c1 * z, y + d1], axis=1)
    return p_base @ R_wb.T + p_wb


def check_vertical(tr: Trajectory, moves: Sequence[Move], station: Station, tol_m: float) -> tuple[list[str], float]:
    """FK at every sample of the vertical phases: suction point within ``tol_m`` of the block's vertical line.

    Returns (violations, worst deviation [m]).
    """
    out: list[str] = []
    vert = np.flatnonzero(np.isin(tr.phase, [int(p) for p in VERTICAL_PHASES]))
    if vert.size == 0:
        return out, 0.0
    # The slot of every vertical sample: the move's source while picking/lifting, else its destination.
    src = np.array([(m.from_tower, m.from_height) for m in moves], dtype=int).reshape(-1, 2)
    dst = np.array([(m.to_tower, m.to_height) for m in moves], dtype=int).reshape(-1, 2)
    mi = tr.move_index[vert]
    at_src = np.isin(tr.phase[vert], [int(Phase.DESCEND_PICK), int(Phase.LIFT)])
    slot = np.where(at_src[:, None], src[mi], dst[mi])
    line_xy = np.array([[contact_point_world(station, t, h)[:2] for h in range(station.n_heights)]
                        for t in range(station.n_towers)])
    p = tcp_positions_world(station, tr.q[vert])
    dev = np.linalg.norm(p[:, :2] - line_xy[slot[:, 0], slot[:, 1]], axis=1)
    for i in np.flatnonzero(dev > tol_m)[:5]:
        k, (tower, height) = vert[i], slot[i]
        out.append(f"suction point {dev[i] * 1e3:.2f} mm off the vertical line of tower {tower + 1} height "
                   f"{height + 1} at t = {tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name}, move "
                   f"{tr.move_index[k] + 1}); allowed {tol_m * 1e3:.1f} mm")
    return out, float(np.max(dev))

