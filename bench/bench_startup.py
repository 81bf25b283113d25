#!/usr/bin/env python3
"""Benchmark start-up: `--help` of every command, a cold `plan`, `tables`, and IK per pose and per 18-pose table.

Usage: .venv/bin/python bench/bench_startup.py [--runs N]
Targets (issue 27): every `--help` <= 0.08 s; cold `plan` on a shipped station (its entries in the user cache)
<= 0.30 s; `tables` <= 0.25 s with no cache at all; an 18-pose IK table <= 1 ms.

Each command is a new process of this interpreter (`python -m ur3hanoi ...`, as a fresh clone runs it), timed from
start to exit; figures are the median (and best) of N runs after one warm-up run, with the median CPU time (user +
system) of the process. The interpreter's floor and every `--help` run in interleaved rounds (one of each per
round). Byte code is cached as after an install (PYTHONDONTWRITEBYTECODE is dropped; the cache goes to a temporary
PYTHONPYCACHEPREFIX), and the user's cache is a temporary XDG_CACHE_HOME: the first `plan` of a station fills it
(the planner's connections and waypoints, the collision geometry; reported apart), the timed ones use it. `tables`
keeps nothing in the user cache: every run reads the calibration, solves the IK and writes the file.
Wall times on a shared machine grow with its load (printed beside them); the CPU time of a single-threaded command
does not wait for a core (the command keeps numpy's BLAS on one thread, see ur3hanoi/cli/__init__.py).
"""

from __future__ import annotations

import argparse
import contextlib
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import NamedTuple

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

HELP_TARGET_S, PLAN_TARGET_S, TABLES_TARGET_S, TABLE_IK_TARGET_MS = 0.08, 0.30, 0.25, 1.0

STUDENT_HEAD = """\
# Lab 2 waypoints (mine)
home_pos: [0.0, -1.5708, 0.0, -1.5708, 0.0, 0.0]
sim_pos: old  # to be regenerated
notes:
  - recorded on station 4
"""


def student_file() -> str:
    """A student's lab file: keys of their own, a stale ``sim_pos`` and the shipped ``real_pos`` (18 poses)."""
    shipped = (REPO / "tables" / "lab2_data.yaml").read_text(encoding="utf-8")
    start = re.search(r"^# ur3hanoi [^\n]*: real_pos ", shipped, re.M)
    assert start is not None, "tables/lab2_data.yaml has no real_pos"
    return STUDENT_HEAD + shipped[start.start():]


def machine() -> str:
    cpu = platform.processor() or "?"
    with contextlib.suppress(OSError, StopIteration):
        cpu = next(ln.split(":", 1)[1].strip() for ln in Path("/proc/cpuinfo").read_text().splitlines()
                   if ln.startswith("model name"))
    return f"{cpu}, {os.cpu_count()} cores, Python {platform.python_version()}"


def load_average() -> str:
    try:
        return f"{os.getloadavg()[0]:.1f}"
    except OSError:
        return "?"


class Runner:
    """Runs ``python -m ur3hanoi ARGS`` in a fresh process with a private byte-code and user cache."""

    def __init__(self, tmp: Path) -> None:
        self.env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        self.env.update(PYTHONPYCACHEPREFIX=str(tmp / "pycache"), XDG_CACHE_HOME=str(tmp / "xdg"),
                        PYTHONPATH=os.pathsep.join(filter(None, (str(REPO), os.environ.get("PYTHONPATH")))))
        self.tmp = tmp

    def once(self, argv: Sequence[str], **env: str) -> Timing:
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run([sys.executable, *argv], cwd=self.tmp, env={**self.env, **env}, stdout=subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True, check=False)
        wall = time.perf_counter() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        if proc.returncode != 0:
            raise SystemExit(f"{' '.join(argv)} failed (exit {proc.returncode}): {proc.stderr.strip()[-500:]}")
        return Timing(wall, r1.ru_utime - r0.ru_utime + r1.ru_stime - r0.ru_stime)

    def timed(self, argv: Sequence[str], runs: int, warm_up: bool = True) -> list[Timing]:
        if warm_up:
            self.once(argv)
        return [self.once(argv) for _ in range(runs)]

    def rounds(self, argvs: Sequence[Sequence[str]], runs: int) -> list[list[Timing]]:
        """Each of ``argvs`` once per round, ``runs`` rounds after a warm-up round: a slow spell of a shared
        machine then slows every command (and the floor) alike instead of whichever was running."""
        for argv in argvs:
            self.once(argv)
        timings: list[list[Timing]] = [[] for _ in argvs]
        for _ in range(runs):
            for argv, out in zip(argvs, timings, strict=True):
                out.append(self.once(argv))
        return timings


class Timing(NamedTuple):
    """One run: wall time [s] from start to exit, and the process's CPU time [s] (user + system)."""

    wall: float
    cpu: float


def summary(runs: list[Timing], target_s: float | None = None) -> str:
    """Wall median and best, and the median CPU time: on a busy machine the wall time includes waiting for a core,
    the CPU time does not (for a single-threaded command it is what the wall time is on an idle machine)."""
    walls = [r.wall for r in runs]
    text = (f"wall median {statistics.median(walls):.3f} s, best {min(walls):.3f} s; CPU median "
            f"{statistics.median(r.cpu for r in runs):.3f} s ({len(runs)} runs")
    return text + (f"; target <= {target_s:g} s)" if target_s is not None else ")")


def per_call_us(fn: Callable[[], object], repeats: int) -> float:
    fn()  # warm-up
    samples = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        samples.append(time.perf_counter() - t0)
    return statistics.median(samples) * 1e6


def bench_ik_station(name: str, repeats: int) -> list[str]:
    from ur3hanoi.robot.ik import analytic_ik, branch_of, closed_form_result, solve_on_branch, solve_table_on_branch
    from ur3hanoi.robot.ik_solvers import SOLVERS, IKSolver, make_solver
    from ur3hanoi.robot.model import load_ur3
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.station.grid import T_base_tcp
    from ur3hanoi.tables.ik_table import generate_table

    station = load_station(name)
    robot = load_ur3(station.tool, station.limits)
    q_home = station.q_home_array
    home = branch_of(q_home)
    targets = [T_base_tcp(station, t, h, k) for t in range(station.n_towers) for h in range(station.n_heights)
               for k in (0, 1)]
    seeds = [analytic_ik(T * robot.T_tcp_tool0, only=home)[home] for T in targets]
    pairs = list(zip(targets, seeds, strict=True))
    solvers = {s: make_solver(s, robot) for s in SOLVERS}
    n = len(targets)
    pose_us = per_call_us(lambda: [solve_on_branch(solvers["pinocchio"], T, q_home, home_branch=home)
                                   for T in targets], repeats)
    labels = [f"pose {i}" for i in range(n)]
    table_us = per_call_us(lambda: solve_table_on_branch(solvers["pinocchio"], targets, q_home, labels, home), repeats)
    closed_us = per_call_us(lambda: [closed_form_result(robot, T, q) for T, q in pairs], repeats)

    def refine_all(solver: IKSolver) -> Callable[[], object]:
        return lambda: [solver.solve(T, q) for T, q in pairs]

    refine_us = {s: per_call_us(refine_all(solver), max(3, repeats // 10)) for s, solver in solvers.items()}
    generate_us = per_call_us(lambda: generate_table(station, solvers["pinocchio"]), repeats)
    refined = sum(r.iterations > 0 for r in generate_table(station, "pinocchio").results)
    return [
        f"IK {name}: {pose_us / n:.1f} us per pose alone ({refined} of {n} poses refined; the NumPy FK check of the "
        f"closed form {closed_us / n:.1f} us of it); refining a pose instead costs "
        + ", ".join(f"{s} {us / n:.1f} us" for s, us in refine_us.items()),
        f"IK {name}: {n}-pose table median {table_us / 1e3:.3f} ms (target <= {TABLE_IK_TARGET_MS:g} ms; the FK check "
        f"of all poses in one NumPy pass); generate_table with the grid poses {generate_us / 1e3:.3f} ms",
    ]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--runs", type=int, default=10, help="timed runs per command (default 10)")
    args = ap.parse_args()
    from ur3hanoi.cli import build_parser

    commands = list(next(a for a in build_parser()._actions if a.dest == "command").choices or ())
    print(f"machine: {machine()}; load average {load_average()} at start")
    with tempfile.TemporaryDirectory(prefix="ur3hanoi-bench-") as tmp_name:
        run = Runner(Path(tmp_name))
        helps = [["-m", "ur3hanoi", *argv, "--help"] for argv in ([], *([c] for c in commands))]
        floor, *help_runs = run.rounds([["-c", "pass"], *helps], args.runs)
        print(f"python -c pass (the interpreter's own start, the floor): {summary(floor)}")
        for argv, walls in zip(helps, help_runs, strict=True):
            print(f"ur3hanoi {' '.join(argv[2:])}: {summary(walls, HELP_TARGET_S)}")
        warm_up = ["-m", "ur3hanoi", "plan", "--start", "1", "--end", "3"]
        run.once(warm_up, XDG_CACHE_HOME=str(Path(tmp_name) / "throwaway"))  # byte code only, not the user cache
        for station in ("lab_sim", "lab_real"):
            argv = ["-m", "ur3hanoi", "plan", "--start", "1", "--end", "3", "--calibration", station]
            first = run.once(argv)  # nothing of this station in the user cache yet (the robot's geometry may be)
            print(f"cold ur3hanoi plan --start 1 --end 3 --calibration {station}: "
                  f"{summary(run.timed(argv, args.runs, warm_up=False), PLAN_TARGET_S)} with its entries in the "
                  f"user cache; first run (nothing of the station cached) wall {first.wall:.3f} s, "
                  f"CPU {first.cpu:.3f} s")
        out = str(Path(tmp_name) / "lab2_data.yaml")
        argv = ["-m", "ur3hanoi", "tables", "lab_sim", "--key", "sim_pos", "-o", out]
        print(f"ur3hanoi tables lab_sim --key sim_pos -o FILE: {summary(run.timed(argv, args.runs), TABLES_TARGET_S)} "
              "rerun on its own output (no cache: the station read, the IK solved, the file parsed and written)")
        student = Path(tmp_name) / "student.yaml"
        argv = ["-m", "ur3hanoi", "tables", "lab_sim", "--key", "sim_pos", "-o", str(student)]
        into_student, text = [], student_file()
        for _ in range(args.runs):  # a student's file with keys of their own and a stale key: read, spliced, checked
            student.write_text(text, encoding="utf-8")
            into_student.append(run.once(argv))
        print(f"ur3hanoi tables lab_sim --key sim_pos -o STUDENT_FILE: {summary(into_student, TABLES_TARGET_S)} "
              f"into a student's file ({len(text)} bytes: keys of their own, a stale sim_pos and a real_pos table; "
              "parsed, spliced and read back)")
    for name in ("lab_sim", "lab_real"):
        for line in bench_ik_station(name, repeats=max(20, args.runs * 20)):
            print(line)
    print(f"load average {load_average()} at end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
