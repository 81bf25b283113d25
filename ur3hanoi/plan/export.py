"""Export of a plan: the trajectory as CSV text and the plan's JSON summary (what ``ur3hanoi plan`` writes)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ur3hanoi.arrays import FloatArray

if TYPE_CHECKING:
    from ur3hanoi.plan.types import Plan, Trajectory


def trajectory_csv(tr: Trajectory) -> str:
    """CSV text: header ``t,q1..q6,qd1..qd6,suction``; t [s], q [rad], qd [rad/s], suction 0/1."""
    header = ",".join(["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction"])
    lines = [header]
    for k in range(len(tr.t)):
        vals = [f"{tr.t[k]:.6f}", *(repr(float(x)) for x in tr.q[k]), *(repr(float(x)) for x in tr.qd[k]),
                "1" if tr.suction[k] else "0"]
        lines.append(",".join(vals))
    return "\n".join(lines) + "\n"


def plan_json_dict(plan: Plan) -> dict[str, Any]:
    """JSON-ready summary of ``plan``; towers, heights and blocks numbered from 1 (block 1 = bottom/largest)."""
    tr = plan.trajectory
    lim = plan.limits

    def vec(a: FloatArray) -> list[float]:
        return [float(x) for x in a]

    return {
        "station": plan.station.name,
        "start_tower": plan.start + 1,
        "end_tower": plan.end + 1,
        "blocks": plan.n_blocks,
        "moves": [m.as_lab_dict() for m in plan.moves],
        "duration_s": plan.duration_s,
        "stop_and_go_duration_s": plan.stop_and_go_duration_s,
        "motion_s": plan.motion_s,
        "stop_and_go_motion_s": plan.stop_and_go_motion_s,
        "dwell_s": plan.config.dwell_s,
        "speed": plan.config.speed,
        "rate_hz": tr.rate_hz,
        "samples": len(tr.t),
        "max_abs_velocity": vec(np.max(np.abs(tr.qd), axis=0)),
        "max_abs_acceleration": vec(np.max(np.abs(tr.qdd), axis=0)),
        "max_abs_jerk": vec(np.max(np.abs(tr.qddd), axis=0)),
        "velocity_limit": vec(lim.v_max) if lim is not None else [],
        "acceleration_limit": vec(lim.a_max) if lim is not None else [],
        "jerk_limit": vec(lim.j_max) if lim is not None else [],
        "violations": list(plan.violations),
        "planning_time_s": dict(plan.timings_s),
    }
