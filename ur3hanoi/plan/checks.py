"""Safety checks of a sampled plan: joint limits (position, velocity, acceleration, jerk) and the vertical line.

Both return human-readable violations (empty: the check passed); :func:`ur3hanoi.plan.plan_moves` collects them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.grid import contact_point_world
from ur3hanoi.hanoi import Move
from ur3hanoi.plan.types import VERTICAL_PHASES, KinematicLimits, Phase, Segment, Trajectory
from ur3hanoi.robot import dh_fk, load_ur3
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


def tcp_positions_world(station: Station, q: FloatArray) -> FloatArray:
    """World position [m] of the suction point at every row of ``q`` (N, 6): batched UR3 DH forward kinematics.

    Same kinematics as ``Ur3Model.fk(q, "tcp")`` (the URDF and the DH table agree to ~1e-11 m), without a
    per-sample Pinocchio call.
    """
    T = dh_fk(q)
    t_flange_tcp = load_ur3(station.tool, station.limits).T_flange_tcp("tool0").translation
    p_base = T[:, :3, :3] @ t_flange_tcp + T[:, :3, 3]
    T_wb = station.T_world_base
    return p_base @ T_wb.rotation.T + T_wb.translation


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

