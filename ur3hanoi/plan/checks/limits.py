"""Joint limits of a sampled plan: position (between samples too), velocity, acceleration and jerk.

Returns human-readable violations (empty: the check passed); :func:`ur3hanoi.plan.plan_moves` collects them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.plan.types import KinematicLimits, Phase, Segment, Trajectory

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
