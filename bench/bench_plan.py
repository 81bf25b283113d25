"""Benchmark (not a test): planning time per move for N = 1..10 blocks on a tall synthetic grid, and the 3-block
lab cycle time against stop-and-go of the same waypoints under the same limits.

Run: ``.venv/bin/python bench/bench_plan.py``. Collision checks are off for the scaling table (reported apart).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

from ur3hanoi.plan import PlanConfig, build_waypoints, plan_solve
from ur3hanoi.station import load_station

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    real = load_station(ROOT / "robots/stations/lab_real.yaml")
    # Tall synthetic grid: lab_real with 10 levels; towers moved closer to the base so the top levels stay reachable.
    tall = dataclasses.replace(real, n_heights=10, tower_origins=tuple((0.22, y, z) for _, y, z in real.tower_origins))
    t0 = time.perf_counter()
    build_waypoints(tall)
    print(f"tall grid waypoints (table + vertical paths, cached): {time.perf_counter() - t0:.2f} s")
    print(f"{'N':>3} {'moves':>6} {'ruckig ms':>10} {'ms/move':>8} {'build ms/move':>14} {'sample ms/move':>15}")
    cfg = PlanConfig(check_collisions=False)
    for n in range(1, 11):
        plan = plan_solve(tall, 0, 2, n, cfg)
        m = len(plan.moves)
        ts = plan.timings_s
        print(f"{n:>3} {m:>6} {ts['ruckig'] * 1e3:>10.2f} {ts['ruckig'] * 1e3 / m:>8.3f} "
              f"{ts['build'] * 1e3 / m:>14.3f} {ts['sampling'] * 1e3 / m:>15.3f}")
    for name in ("lab_sim", "lab_real"):
        st = load_station(ROOT / f"robots/stations/{name}.yaml")
        plan_solve(st, 0, 2, 1)  # warm the waypoint cache
        plan = plan_solve(st, 0, 2, 3)
        ts = plan.timings_s
        print(f"{name} 3 blocks: cycle {plan.duration_s:.3f} s, stop-and-go {plan.stop_and_go_duration_s:.3f} s; "
              f"motion {plan.motion_s:.3f} s vs {plan.stop_and_go_motion_s:.3f} s -> "
              f"{100 * plan.motion_saving:.1f} % less; ruckig {ts['ruckig'] * 1e3 / len(plan.moves):.3f} ms/move, "
              f"collision check {ts.get('collision', 0.0) * 1e3:.0f} ms, limit+vertical checks "
              f"{ts['checks'] * 1e3:.0f} ms")


if __name__ == "__main__":
    main()
