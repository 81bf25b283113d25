"""Benchmark (not a test): the plan's motion time against the honest stop-and-go baseline, and planning time.

Run: ``.venv/bin/python bench/bench_plan.py``. Reports, in one run:

1. 3 blocks, tower 1 -> 3, on lab_sim and lab_real: the honest baseline (joint-space Ruckig from rest to rest
   between the same waypoints, same limits and dwells), the plan, their ratio (target <= 0.85, goal 0.80), the
   exact-vertical stop-and-go (approach/retreat on the exact line, constant path limits: the old reference), time
   per leg type (vertical legs, motion across) for the three, and the worst distance from the vertical line by
   forward kinematics at 1 kHz.
2. Cold ``ur3hanoi plan --start 1 --end 3`` (process start to exit, clearance checks included; target < 1 s).
3. Planning time per move for N = 1..10 blocks on a tall synthetic grid (lab_real with 10 levels, towers pulled in
   so the top levels stay reachable), clearance checks included: each N in a fresh process. "set-up" is the
   one-off per-station part (IK table, vertical paths, collision scene; target < 1 s); "cold" the first plan after
   it (legs and connections built on demand, per move; target < 5 ms), "warm" the same plan again (everything
   cached). Linear in moves is the target.
"""

from __future__ import annotations

import dataclasses
import itertools
import json
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
VERTICAL = ("DESCEND_PICK", "LIFT", "DESCEND_PLACE", "RETREAT")
ACROSS = ("TRANSIT", "CARRY", "HOME")


def _tall():  # type: ignore[no-untyped-def]
    from ur3hanoi.station import load_station

    real = load_station("lab_real")
    return dataclasses.replace(real, n_heights=10, tower_origins=tuple((0.22, y, z) for _, y, z in real.tower_origins))


def one(n: int) -> None:
    """Child process: set-up, cold and warm planning of N blocks on the tall grid; prints one JSON line."""
    t0 = time.perf_counter()
    from ur3hanoi.plan import plan_solve
    from ur3hanoi.plan.clearance import clearance_cache
    from ur3hanoi.plan.types import PlanConfig
    from ur3hanoi.plan.waypoints import build_waypoints, geometry_key

    t_import = time.perf_counter() - t0
    tall = _tall()
    cfg = PlanConfig()
    lim = cfg.limits(tall)
    t0 = time.perf_counter()
    build_waypoints(tall)
    key = (tuple(lim.v_max.tolist()), tuple(lim.a_max.tolist()), tuple(lim.j_max.tolist()))
    clearance_cache(geometry_key(tall), key, 1.0 / cfg.collision_rate_hz)
    setup = time.perf_counter() - t0
    t0 = time.perf_counter()
    plan = plan_solve(tall, 0, 2, n, cfg)
    cold = time.perf_counter() - t0
    cold_timings = dict(plan.timings_s)
    warm = []
    for _ in range(2 if n < 9 else 1):
        t0 = time.perf_counter()
        plan = plan_solve(tall, 0, 2, n, cfg)
        warm.append(time.perf_counter() - t0)
    print(json.dumps({"n": n, "moves": len(plan.moves), "samples": len(plan.trajectory.t), "import": t_import,
                      "setup": setup, "cold": cold, "warm": min(warm), "timings": cold_timings,
                      "ratio": plan.motion_s / plan.stop_and_go_motion_s, "violations": len(plan.violations)}))


def leg_times(plan) -> tuple[float, float]:  # type: ignore[no-untyped-def]
    """Summed duration [s] of the plan's vertical legs and of its motions across."""
    vert = sum(s.duration for s in plan.segments if s.trajectory is not None and s.phase.name in VERTICAL)
    across = sum(s.duration for s in plan.segments if s.trajectory is not None and s.phase.name in ACROSS)
    return vert, across


def reference_leg_times(plan, exact_vertical: bool) -> tuple[float, float]:  # type: ignore[no-untyped-def]
    """The same split for the honest (or exact-vertical) stop-and-go of the plan's waypoints."""
    from ur3hanoi.plan.builder import plan_hops
    from ur3hanoi.plan.connections import station_planner

    cfg = plan.config
    planner = station_planner(plan.station, plan.limits, cfg.vertical_tol_m, cfg.via_speeds, cfg.via_accels)
    vert = across = 0.0
    for hop in plan_hops(plan.station, plan.moves, plan.n_blocks, plan.start, cfg.clearance_m):
        qs = [planner.q_above(hop.slot0), planner.q_above(hop.slot1)]
        across += sum(planner.rest_to_rest(a, b) for a, b in itertools.pairwise(qs))
        for slot in (hop.slot0, hop.slot1):
            if slot is not None:
                vert += (planner.exact_vertical_leg(slot) if exact_vertical
                         else planner.rest_to_rest(planner.q_above(slot), planner.wp.table[slot[0], slot[1], 0]))
    return vert, across


def lab() -> None:
    from ur3hanoi.plan import PlanConfig, plan_solve
    from ur3hanoi.station import load_station

    print("3 blocks, tower 1 -> 3: motion time [s] (dwells excluded); legs = approach/retreat, across = transit/carry/"
          "home")
    print(f"{'station':<9} {'honest':>8} {'plan':>8} {'ratio':>6} {'exact-v':>8} | {'legs: honest':>12} {'plan':>6} "
          f"{'exact-v':>7} | {'across: honest':>14} {'plan':>6} | {'max dev':>8}")
    for name in ("lab_sim", "lab_real"):
        st = load_station(name)
        plan = plan_solve(st, 0, 2, 3, PlanConfig())
        v, a = leg_times(plan)
        hv, ha = reference_leg_times(plan, exact_vertical=False)
        ev, _ = reference_leg_times(plan, exact_vertical=True)
        ratio = plan.motion_s / plan.stop_and_go_motion_s
        print(f"{name:<9} {plan.stop_and_go_motion_s:>8.3f} {plan.motion_s:>8.3f} {ratio:>6.3f} "
              f"{plan.exact_vertical_stop_and_go_motion_s:>8.3f} | {hv:>12.3f} {v:>6.3f} {ev:>7.3f} | {ha:>14.3f} "
              f"{a:>6.3f} | {plan.vertical_deviation_m * 1e3:>5.2f} mm")
        n_legs = sum(1 for s in plan.segments if s.phase.name in VERTICAL and s.target.split("(")[0] in ("on", "above"))
        print(f"          per leg: honest {hv / n_legs:.3f} s, plan {v / n_legs:.3f} s, exact-vertical "
              f"{ev / n_legs:.3f} s ({n_legs} legs); ratio {'within' if ratio <= 0.85 else 'OVER'} 0.85 "
              f"({'goal 0.80 met' if ratio <= 0.80 else 'goal 0.80 not met'}); {len(plan.violations)} violations")


def cli() -> None:
    walls = []
    for name in ("lab_sim", "lab_real"):
        for _ in range(3):
            t0 = time.perf_counter()
            proc = subprocess.run([str(Path(sys.executable).parent / "ur3hanoi"), "plan", "--start", "1", "--end", "3",
                                   "--calibration", name], capture_output=True, text=True, cwd=ROOT)
            walls.append((name, time.perf_counter() - t0, proc.returncode))
    for name in ("lab_sim", "lab_real"):
        w = [x for n, x, _ in walls if n == name]
        rc = {r for n, _, r in walls if n == name}
        print(f"cold `ur3hanoi plan --start 1 --end 3 --calibration {name}`: best {min(w):.3f} s, median "
              f"{statistics.median(w):.3f} s (exit {sorted(rc)}; target < 1 s)")


def scaling() -> None:
    print("tall grid (10 levels), clearance checks included; per move [ms] unless noted; each N in a fresh process")
    print(f"{'N':>3} {'moves':>6} {'set-up s':>9} {'cold':>7} {'warm':>7} | cold: {'build':>6} {'sample':>7} "
          f"{'checks':>7} {'clear.':>7} | {'ratio':>6}")
    worst_cold = worst_warm = worst_setup = 0.0
    fit: list[tuple[int, float, float]] = []
    for n in range(1, 11):
        out = subprocess.run([sys.executable, __file__, "--one", str(n)], capture_output=True, text=True, cwd=ROOT)
        if out.returncode != 0:
            print(f"{n:>3} FAILED: {out.stderr.strip()[-300:]}")
            continue
        d = json.loads(out.stdout.strip().splitlines()[-1])
        m = d["moves"]
        t = d["timings"]
        worst_cold, worst_warm = max(worst_cold, d["cold"] / m), max(worst_warm, d["warm"] / m)
        worst_setup = max(worst_setup, d["setup"])
        fit.append((m, d["cold"], d["warm"]))
        print(f"{n:>3} {m:>6} {d['setup']:>9.3f} {d['cold'] / m * 1e3:>7.2f} {d['warm'] / m * 1e3:>7.2f} | "
              f"{'':>5} {t['build'] / m * 1e3:>6.2f} {t['sampling'] / m * 1e3:>7.2f} {t['checks'] / m * 1e3:>7.2f} "
              f"{t.get('collision', 0.0) / m * 1e3:>7.2f} | {d['ratio']:>6.3f}"
              + (f"  {d['violations']} violations" if d["violations"] else ""))
    print(f"worst: set-up {worst_setup:.3f} s (target < 1 s), cold {worst_cold * 1e3:.2f} ms/move, warm "
          f"{worst_warm * 1e3:.2f} ms/move (target < 5 ms)")
    if len(fit) >= 2:
        # Least squares total = fixed + per_move * moves: the first plan's legs and connections are built once per
        # station and reused by every later move (the fixed part); what each further move costs is the slope.
        for name, col in (("cold", 1), ("warm", 2)):
            moves = [f[0] for f in fit]
            totals = [f[col] for f in fit]
            mm, mt = statistics.fmean(moves), statistics.fmean(totals)
            cov = sum((x - mm) * (y - mt) for x, y in zip(moves, totals, strict=True))
            slope = cov / sum((x - mm) ** 2 for x in moves)
            print(f"{name} planning time = {mt - slope * mm:.3f} s + {slope * 1e3:.2f} ms x moves (least squares, "
                  "N = 1..10)")


def main() -> None:
    lab()
    print()
    cli()
    print()
    scaling()


if __name__ == "__main__":
    if len(sys.argv) == 3 and sys.argv[1] == "--one":
        one(int(sys.argv[2]))
    else:
        main()
