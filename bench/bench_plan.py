"""Benchmark (not a test): planning time per move for N = 1..10 blocks on a tall synthetic grid, and the 3-block
lab cycle time against stop-and-go of the same waypoints under the same limits.

Run: ``.venv/bin/python bench/bench_plan.py``. Collision checks are off for the scaling table (reported apart).

Headline ("plan ms/move"): build + sampling per move, where build includes its Ruckig ``calculate`` calls (the
"ruckig" column is that share of build, not an extra term). Not included: the cached waypoints, the stop-and-go
reference plan ("s&g") and the limit/vertical checks ("checks"), shown separately; "all" is plan + s&g + checks.
The waypoints (IK table + vertical paths) are built once per station and cached (timed apart, first line); the
planning times are of warm calls, but every plan solves its own Ruckig problems (nothing Ruckig is cached across
plans). Each row, and each lab line, is the fastest of a few runs (other processes share the machine).
"""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path

from ur3hanoi.plan import PlanConfig, build_waypoints, plan_solve
from ur3hanoi.resources import stations_dir
from ur3hanoi.station import load_station

ROOT = Path(__file__).resolve().parents[1]
TARGET_MS_PER_MOVE = 2.0


def main() -> None:
    real = load_station(stations_dir() / "lab_real.yaml")
    # Tall synthetic grid: lab_real with 10 levels; towers moved closer to the base so the top levels stay reachable.
    tall = dataclasses.replace(real, n_heights=10, tower_origins=tuple((0.22, y, z) for _, y, z in real.tower_origins))
    t0 = time.perf_counter()
    build_waypoints(tall)
    print(f"tall grid waypoints (table + vertical paths, cached): {time.perf_counter() - t0:.2f} s")
    print(f"per move [ms] at 125 Hz; plan = build (incl. ruckig) + sampling; target < {TARGET_MS_PER_MOVE:g} ms/move; "
          "not in plan: waypoints (cached), s&g reference, checks")
    print(f"{'N':>3} {'moves':>6} {'samples':>8} {'plan':>7} {'ruckig':>7} {'build':>7} {'sample':>7} {'s&g':>7} "
          f"{'checks':>7} {'all':>7}")
    cfg = PlanConfig(check_collisions=False)
    worst = 0.0
    for n in range(1, 11):
        best: dict[str, float] | None = None
        samples = m = 0
        for _ in range(5 if n <= 6 else 2 if n <= 8 else 1):
            plan = plan_solve(tall, 0, 2, n, cfg)
            m, samples = len(plan.moves), len(plan.trajectory.t)
            ts = dict(plan.timings_s)
            ts["plan"] = ts["build"] + ts["sampling"]
            if best is None or ts["plan"] < best["plan"]:
                best = ts
        assert best is not None
        per = {k: v * 1e3 / m for k, v in best.items()}
        worst = max(worst, per["plan"])
        print(f"{n:>3} {m:>6} {samples:>8} {per['plan']:>7.3f} {per['ruckig']:>7.3f} {per['build']:>7.3f} "
              f"{per['sampling']:>7.3f} {per['stop_and_go']:>7.3f} {per['checks']:>7.3f} "
              f"{per['plan'] + per['stop_and_go'] + per['checks']:>7.3f}")
    print(f"worst plan time per move: {worst:.3f} ms ({'within' if worst < TARGET_MS_PER_MOVE else 'OVER'} the "
          f"{TARGET_MS_PER_MOVE:g} ms target)")
    for name in ("lab_sim", "lab_real"):
        st = load_station(stations_dir() / f"{name}.yaml")
        plan_solve(st, 0, 2, 1)  # warm the waypoint cache
        runs = [plan_solve(st, 0, 2, 3) for _ in range(5)]  # with clearance checks, as the CLI plans
        plan = min(runs, key=lambda p: p.timings_s["build"] + p.timings_s["sampling"])
        ts = plan.timings_s
        m = len(plan.moves)
        print(f"{name} 3 blocks: cycle {plan.duration_s:.3f} s, stop-and-go {plan.stop_and_go_duration_s:.3f} s; "
              f"motion {plan.motion_s:.3f} s vs {plan.stop_and_go_motion_s:.3f} s -> "
              f"{100 * plan.motion_saving:.1f} % less; plan {(ts['build'] + ts['sampling']) * 1e3 / m:.3f} ms/move "
              f"(ruckig {ts['ruckig'] * 1e3 / m:.3f}), collision check {ts.get('collision', 0.0) * 1e3:.0f} ms, "
              f"limit+vertical checks {ts['checks'] * 1e3:.0f} ms")


if __name__ == "__main__":
    main()
