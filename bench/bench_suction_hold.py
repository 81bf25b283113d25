"""Benchmark (not a test): how hard the simulated suction is pulled while carrying, against the planner's jerk limit.

Run: ``.venv/bin/python bench/bench_suction_hold.py``. For the 3-block solve on lab_sim and lab_real, planned with
the jerk limit scaled by 1..100 (acceleration caps fixed at 4/8 rad/s^2, datasheet speeds), executes each plan in
MuJoCo and records, at every control cycle of a carrying phase, the weld's stretch (how far the held block's centre
is from where the suction holds it: :meth:`ur3hanoi.sim.SuctionCup.stretch`) and the suction point's acceleration
(world frame, from the plan's samples). The seal counts as broken beyond ``SuctionConfig.hold_tolerance`` (10 mm);
the jerk limit's default (:data:`ur3hanoi.robot.model.DEFAULT_JERK_MAX`) is the largest of these scales whose worst
stretch stays within a quarter of it (margin 4) and whose plan still passes its own checks.
"""

from __future__ import annotations

import sys

import numpy as np

SCALES = (1.0, 2.0, 5.0, 10.0, 25.0, 50.0, 100.0)  # 25: the default, 500/1000 rad/s^3
BASE = (20.0, 20.0, 20.0, 40.0, 40.0, 40.0)  # [rad/s^3] the former default the scales multiply


def measure(name: str, scale: float) -> tuple[float, float, float, str, float]:
    """(worst stretch [m], worst |a - g| of the suction point while carrying [m/s^2], motion [s], status, stretch
    per |a - g| [m per m/s^2], least squares over the carrying cycles)."""
    from ur3hanoi.plan import Phase, PlanConfig, plan_solve
    from ur3hanoi.plan.kinematics import tcp_positions_world
    from ur3hanoi.sim import executor
    from ur3hanoi.sim.suction import SuctionCup
    from ur3hanoi.station.calibration import load_station

    st = load_station(name)
    plan = plan_solve(st, 0, 2, 3, PlanConfig(j_max=tuple(j * scale for j in BASE)))
    tr = plan.trajectory
    carrying = np.isin(tr.phase, [p for p in Phase if p.carrying])
    p = tcp_positions_world(st, tr.q)
    acc = np.gradient(np.gradient(p, tr.t, axis=0), tr.t, axis=0)
    pull = np.linalg.norm(acc - np.array([0.0, 0.0, -9.81]), axis=1)  # what the seal must supply, per kg
    worst_acc = float(np.max(pull[carrying]))
    samples: list[tuple[float, float]] = []
    update = SuctionCup.update

    def spy(cup: SuctionCup) -> None:
        k = min(round(float(cup.scene.data.time) * tr.rate_hz), len(tr.t) - 1)
        if carrying[k] and cup.attached is not None:
            samples.append((float(pull[k]), cup.stretch()))
        update(cup)

    SuctionCup.update = spy  # type: ignore[method-assign]
    try:
        result = executor.run_plan(plan)
    finally:
        SuctionCup.update = update  # type: ignore[method-assign]
    a, x = np.array(samples).T
    return float(x.max()), worst_acc, plan.motion_s, result.status, float(a @ x / (a @ a))


def main() -> None:
    print("3 blocks, tower 1 -> 3; jerk = scale x 20/40 rad/s^3 (joints 1-3 / wrists); a = 4/8 rad/s^2")
    print(f"{'station':<9} {'scale':>6} {'motion s':>9} {'carry |a-g| m/s^2':>18} {'worst stretch mm':>17} "
          f"{'mm per m/s^2':>13} {'sim':>7}")
    slopes = []
    for name in ("lab_sim", "lab_real"):
        for s in SCALES:
            stretch, acc, motion, status, slope = measure(name, s)
            slopes.append(slope)
            print(f"{name:<9} {s:>6g} {motion:>9.2f} {acc:>18.2f} {stretch * 1e3:>17.3f} {slope * 1e3:>13.4f} "
                  f"{status:>7}", flush=True)
    worst_slope = max(slopes)
    print(f"seal limit: SuctionConfig.hold_tolerance = 10 mm of stretch; worst stretch per |a - g| "
          f"{worst_slope * 1e3:.4f} mm per m/s^2 -> the simulated seal holds up to |a - g| = "
          f"{0.010 / worst_slope:.0f} m/s^2 (plan check default: a quarter of it)")


if __name__ == "__main__":
    sys.exit(main())
