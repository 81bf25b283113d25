"""Export of a plan: the trajectory as CSV text and the plan's JSON summary (what ``ur3hanoi plan`` writes)."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.types import Phase

if TYPE_CHECKING:
    from ur3hanoi.plan.types import Plan, Trajectory


def trajectory_csv(tr: Trajectory) -> str:
    """CSV text: header ``t,q1..q6,qd1..qd6,suction,move,phase``; t [s], q [rad], qd [rad/s], suction 0/1, move
    the 1-based move number (0 before the first move and on the way home), phase the :class:`Phase` name."""
    header = ",".join(["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction", "move",
                       "phase"])
    names = {int(p): p.name for p in Phase}
    lines = [header]
    for k in range(len(tr.t)):
        vals = [f"{tr.t[k]:.6f}", *(repr(float(x)) for x in tr.q[k]), *(repr(float(x)) for x in tr.qd[k]),
                "1" if tr.suction[k] else "0", str(int(tr.move_index[k]) + 1), names[int(tr.phase[k])]]
        lines.append(",".join(vals))
    return "\n".join(lines) + "\n"


def move_timeline(plan: Plan) -> list[dict[str, Any]]:
    """Per move (1-based): its start and end [s] (from leaving the previous place, or home, to the end of its
    release dwell) and the waypoints it reaches in order: pose (``above``, ``on``, ``over``), 1-based tower and
    height, the time it is reached [s] and the joints there [rad]. The way home is the last entry, move 0."""
    out: list[dict[str, Any]] = []
    current: dict[str, Any] | None = None
    for seg in plan.segments:
        number = seg.move_index + 1 if seg.phase != Phase.HOME else 0
        if seg.phase == Phase.RETREAT:  # the retreat after a place starts the next hop
            number = seg.move_index + 2 if seg.move_index + 1 < len(plan.moves) else 0
        if current is None or current["move"] != number:
            current = {"move": number, "start_s": seg.t_start, "end_s": seg.t_end, "waypoints": []}
            out.append(current)
        current["end_s"] = seg.t_end
        pose, _, rest = seg.target.partition("(")
        if pose in ("above", "on", "over") and seg.trajectory is not None:
            tower, height = (int(x[1:]) for x in rest.rstrip(")").split(","))
            current["waypoints"].append({"pose": pose, "tower": tower, "height": height, "t_s": seg.t_end,
                                         "q": [float(x) for x in seg.q_end]})
        elif pose == "home":
            current["waypoints"].append({"pose": "home", "t_s": seg.t_end, "q": [float(x) for x in seg.q_end]})
    return out


def plan_json_dict(plan: Plan) -> dict[str, Any]:
    """JSON-ready summary of ``plan``; towers, heights, blocks and moves numbered from 1 (block 1 = bottom/largest).

    ``stop_and_go_*`` is the honest baseline (joint-space Ruckig from rest to rest between the same waypoints,
    same limits and dwells), ``motion_ratio`` the plan's motion time over it; ``exact_vertical_stop_and_go_*`` is
    stop-and-go with approach and retreat on the exact vertical line (constant path limits), reported for
    comparison; ``max_vertical_deviation_m`` the worst distance from the vertical line on any approach or retreat
    (forward kinematics at 1 kHz); ``move_times`` is :func:`move_timeline`.
    """
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
        "motion_ratio": plan.motion_s / plan.stop_and_go_motion_s if plan.stop_and_go_motion_s > 0 else None,
        "exact_vertical_stop_and_go_duration_s": plan.exact_vertical_stop_and_go_duration_s,
        "exact_vertical_stop_and_go_motion_s": plan.exact_vertical_stop_and_go_motion_s,
        "max_vertical_deviation_m": plan.vertical_deviation_m,
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
        "move_times": move_timeline(plan),
    }
