"""Benchmark (not a test): IK microseconds per pose for each solver, and `ur3hanoi tables` wall time.

Run: .venv/bin/python bench/bench_ik.py   (targets: 18-pose table < 5 ms of IK compute; `tables` < 1 s)
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ur3hanoi.io.resources import stations_dir
from ur3hanoi.robot.ik import branch_of, solve_on_branch
from ur3hanoi.robot.ik_solvers import SOLVERS, make_solver
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import load_station
from ur3hanoi.station.grid import T_base_tcp

REPO = Path(__file__).resolve().parents[1]


def bench_solver(name: str, station_path: Path, repeats: int = 200) -> dict[str, float]:
    station = load_station(station_path)
    robot = load_ur3(station.tool, station.limits)
    solver = make_solver(name, robot)
    targets = [T_base_tcp(station, t, h, k) for t in range(station.n_towers) for h in range(station.n_heights)
               for k in (0, 1)]
    q_home = station.q_home_array
    home = branch_of(q_home)
    for T in targets:  # warm-up
        solve_on_branch(solver, T, q_home, home_branch=home)
    per_table = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for T in targets:
            solve_on_branch(solver, T, q_home, home_branch=home)
        per_table.append(time.perf_counter() - t0)
    med = float(np.median(per_table))
    return {"us_per_pose": med / len(targets) * 1e6, "ms_per_table": med * 1e3, "poses": len(targets)}


def bench_cli(repeats: int = 5) -> tuple[float, float]:
    """Wall time [s] of ``ur3hanoi tables`` the first time (a new file) and the median of the next ``repeats`` runs
    (the same file rewritten); nothing is cached between them but the byte code."""
    walls = []
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "XDG_CACHE_HOME": f"{tmp}/xdg"}  # never the user's own cache
        for _ in range(repeats + 1):
            t0 = time.perf_counter()
            subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "tables", "lab_sim",
                            "--key", "sim_pos", "-o", f"{tmp}/lab2_data.yaml"], cwd=REPO, check=True,
                           capture_output=True, env=env)
            walls.append(time.perf_counter() - t0)
    return walls[0], float(np.median(walls[1:]))


def main() -> dict[str, object]:
    results: dict[str, object] = {}
    for station in ("lab_sim", "lab_real"):
        for name in SOLVERS:
            r = bench_solver(name, stations_dir() / f"{station}.yaml")
            results[f"ik_{name}_{station}"] = r
            print(f"IK {name:9s} {station:8s}: {r['us_per_pose']:7.1f} us/pose, {r['ms_per_table']:.2f} ms per "
                  f"{r['poses']}-pose table (target < 5 ms)")
    first, again = bench_cli()
    results["tables_cli_wall_s"] = {"first": first, "again": again}
    print(f"`ur3hanoi tables` end to end (lab_sim): {first:.3f} s wall writing a new file, {again:.3f} s (median of "
          "5) rewriting it (no cache; target < 1 s)")
    return results


if __name__ == "__main__":
    out = main()
    if "--json" in sys.argv:
        print(json.dumps(out))
