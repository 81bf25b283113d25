#!/usr/bin/env python3
"""Benchmark the MuJoCo execution: realtime factor of a full 3-block solve headless, and `ur3hanoi solve` end to end.

Usage: .venv/bin/python bench/bench_sim.py [--repeat N]
Target: realtime factor >= 20x on a 2-core machine (sim time / wall time of the execution loop, planning excluded).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from ur3hanoi.io.resources import stations_dir  # noqa: E402
from ur3hanoi.plan import plan_solve  # noqa: E402
from ur3hanoi.sim import run_plan  # noqa: E402
from ur3hanoi.station.calibration import load_station  # noqa: E402


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    for name in ("lab_sim", "lab_real"):
        st = load_station(stations_dir() / f"{name}.yaml")
        t0 = time.perf_counter()
        plan = plan_solve(st, 0, 2, 3)
        t_plan = time.perf_counter() - t0
        rtfs, errs = [], []
        for _ in range(args.repeat):
            r = run_plan(plan)
            assert r.status == "solved", r.error
            rtfs.append(r.realtime_factor)
            errs.append(math.degrees(r.max_tracking_error_rad))
        print(f"{name}: plan {t_plan:.2f} s; sim {r.sim_time_s:.1f} s in {r.wall_time_s:.2f} s wall; realtime factor "
              f"best {max(rtfs):.1f}x median {sorted(rtfs)[len(rtfs) // 2]:.1f}x; max tracking error "
              f"{max(errs):.3f} deg")
    # This interpreter runs the command (`python -m ur3hanoi`), so no `ur3hanoi` on PATH is needed; the checkout
    # is put first on PYTHONPATH like the sys.path line above.
    cmd = [sys.executable, "-m", "ur3hanoi", "solve", "--start", "1", "--end", "3", "--json"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, (str(REPO), os.environ.get("PYTHONPATH"))))}
    t0 = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, cwd=REPO, env=env, check=False)
    wall = time.perf_counter() - t0
    if proc.returncode not in (0, 3) or not proc.stdout.strip():
        print(f"`ur3hanoi solve` failed (exit {proc.returncode}): {proc.stderr.strip()[-500:]}", file=sys.stderr)
        return 1
    out = json.loads(proc.stdout)
    print(f"`ur3hanoi solve --start 1 --end 3` end to end: {wall:.2f} s wall (exit {proc.returncode}, status "
          f"{out['status']}, sim {out['sim_time_s']:.1f} s, loop realtime factor {out['realtime_factor']:.1f}x)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
