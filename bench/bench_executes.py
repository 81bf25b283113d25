"""Benchmark (not a test): every accepted plan executes, at every grid height the stations allow.

Run: ``.venv/bin/python bench/bench_executes.py``. For lab_sim and lab_real (3 levels) and a tall grid (lab_real
with 8 levels, towers pulled in so the top levels stay reachable), ``plan_solve`` + ``run_plan`` (MuJoCo, suction
checks, final check: every block within 5 mm of its slot) for N = 1 .. height blocks, tower 1 -> 3. Prints per run
the status, the moves, the worst horizontal distance of a final block from its slot's centre, and the worst |a - g|
the suction had to hold while carrying (the plan's own suction-hold check).
"""

from __future__ import annotations

import dataclasses
import sys
import time

import numpy as np


def main() -> int:
    from ur3hanoi.errors import Ur3HanoiError
    from ur3hanoi.plan import plan_solve
    from ur3hanoi.plan.checks.suction import check_suction_hold
    from ur3hanoi.sim import run_plan
    from ur3hanoi.sim.scene import slot_centers
    from ur3hanoi.station.calibration import load_station

    real = load_station("lab_real")
    tall = dataclasses.replace(real, name="tall8", n_heights=8,
                               tower_origins=tuple((0.22, y, z) for _, y, z in real.tower_origins))
    grids = [load_station("lab_sim"), real, tall]
    print(f"{'grid':<9} {'N':>3} {'moves':>6} {'status':>8} {'worst xy off mm':>16} {'carry |a-g| m/s^2':>18} "
          f"{'wall s':>7}")
    failed = 0
    for st in grids:
        centres = slot_centers(st)
        for n in range(1, st.n_heights + 1):
            t0 = time.perf_counter()
            try:
                plan = plan_solve(st, 0, 2, n)
                result = run_plan(plan)
                status = result.status
                off = max(float(np.linalg.norm(np.asarray(b.xyz[:2]) - centres[2, i, :2]))
                          for i, b in enumerate(result.final_blocks))
                pull = check_suction_hold(plan.trajectory, st, plan.config.suction_hold_mps2)[1]
                moves = len(plan.moves)
            except Ur3HanoiError as e:
                status, off, pull, moves = f"error: {e}"[:60], float("nan"), float("nan"), 0
            failed += status != "solved"
            print(f"{st.name:<9} {n:>3} {moves:>6} {status:>8} {off * 1e3:>16.2f} {pull:>18.1f} "
                  f"{time.perf_counter() - t0:>7.1f}", flush=True)
    print(f"{'all solved' if not failed else f'{failed} FAILED'} (final check: every block within 5 mm of its slot)")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
