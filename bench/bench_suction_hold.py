"""Benchmark (not a test): how hard the simulated suction is pulled while carrying, against the planner's jerk limit.

Run: ``.venv/bin/python bench/bench_suction_hold.py``. For the 3-block solve on lab_sim and lab_real, planned with
the jerk limit scaled by 1..100 (acceleration caps fixed at 4/8 rad/s^2, datasheet speeds), executes each plan in
MuJoCo and records, at every control cycle of a carrying phase, the weld's stretch (how far the held block's centre
is from where the suction holds it: :meth:`ur3hanoi.sim.SuctionCup.stretch`) and the suction point's acceleration
(world frame, from the plan's samples). The seal counts as broken beyond ``SuctionConfig.hold_tolerance`` (10 mm);
the jerk limit's default (:data:`ur3hanoi.robot.DEFAULT_JERK_MAX`) is the largest of these scales whose worst
stretch stays within a quarter of it (margin 4) and whose plan still passes its own checks.
"""

from __future__ import annotations

import sys

import numpy as np

SCALES = (1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0)
BASE = (20.0, 20.0, 20.0, 40.0, 40.0, 40.0)  # [rad/s^3] the former default the scales multiply


def measure(name: str, scale: float) -> tuple[float, float, float, str]:
    """(worst stretch [m], worst carry acceleration of the suction point [m/s^2], motion [s], status)."""
    from ur3hanoi.plan import Phase, PlanConfig, plan_solve
    from ur3hanoi.plan.checks import tcp_positions_world
    from ur3hanoi.sim import executor
    from ur3hanoi.sim.suction import SuctionCup
    from ur3hanoi.station import load_station

    st = load_station(name)
    plan = plan_solve(st, 0, 2, 3, PlanConfig(j_max=tuple(j * scale for j in BASE)))
    tr = plan.trajectory
    carrying = np.isin(tr.phase, [p for p in Phase if p.carrying])
    p = tcp_positions_world(st, tr.q)
    acc = np.gradient(np.gradient(p, tr.t, axis=0), tr.t, axis=0)
    worst_acc = float(np.max(np.linalg.norm(acc[carrying], axis=1)))
    worst = [0.0]
    update = SuctionCup.update

    def spy(cup: SuctionCup) -> None:
        worst[0] = max(worst[0], cup.stretch())
        update(cup)

    SuctionCup.update = spy  # type: ignore[method-assign]
    try:
        result = executor.run_plan(plan)
    finally:
        SuctionCup.update = update  # type: ignore[method-assign]
    return worst[0], worst_acc, plan.motion_s, result.status


def main() -> None:
    print("3 blocks, tower 1 -> 3; jerk = scale x 20/40 rad/s^3 (joints 1-3 / wrists); a = 4/8 rad/s^2")
    print(f"{'station':<9} {'scale':>6} {'motion s':>9} {'carry acc m/s^2':>16} {'worst stretch mm':>17} {'sim':>7}")
    for name in ("lab_sim", "lab_real"):
        for s in SCALES:
            stretch, acc, motion, status = measure(name, s)
            print(f"{name:<9} {s:>6g} {motion:>9.2f} {acc:>16.2f} {stretch * 1e3:>17.3f} {status:>7}", flush=True)
    print("seal limit: SuctionConfig.hold_tolerance = 10 mm of stretch")


if __name__ == "__main__":
    sys.exit(main())
