#!/usr/bin/env python3
"""Benchmark what choosing the OpenGL platform costs (ur3hanoi.opengl): one probe, the whole choice on a machine
without a display, and a short ``solve --video`` with and without it.

Usage: .venv/bin/python bench/bench_opengl.py [--runs N]

- A probe is a child process that imports MuJoCo and renders one 16x16 frame with one platform. Beside it, its
  floor: the interpreter alone, and the interpreter importing MuJoCo (the part a probe cannot avoid).
- The choice with ``MUJOCO_GL`` unset and no display: one probe where EGL works (two where OSMesa must be used).
- ``solve --start 1 --end 2 --blocks 1 --fps 2 --size 64x48 --video``: with ``MUJOCO_GL`` unset (the command
  probes), against the baseline a user had before, ``MUJOCO_GL=egl`` set by hand with nothing probed (here: the
  value marked verified, as a process ur3hanoi started sees it).

Figures are the median (and best) of N runs after one warm-up, wall time and CPU time (user + system of the
children); the two ``solve`` runs alternate. Wall times on a shared machine grow with its load (printed); CPU
times do not wait for a core.
"""

from __future__ import annotations

import argparse
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from ur3hanoi.opengl import MUJOCO_GL, VERIFIED, choose, probe  # noqa: E402

HEADLESS = {k: v for k, v in os.environ.items() if k not in (MUJOCO_GL, VERIFIED, "DISPLAY", "WAYLAND_DISPLAY")}


def _children_cpu_s() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def timed(fn: Callable[[], object], runs: int) -> tuple[float, float, float]:
    """(median wall [s], best wall [s], median CPU of the children [s]) of ``fn`` over ``runs`` after a warm-up."""
    fn()
    walls, cpus = [], []
    for _ in range(runs):
        c0, t0 = _children_cpu_s(), time.perf_counter()
        fn()
        walls.append(time.perf_counter() - t0)
        cpus.append(_children_cpu_s() - c0)
    return statistics.median(walls), min(walls), statistics.median(cpus)


def interleaved(fns: list[Callable[[], object]], runs: int) -> list[tuple[float, float, float]]:
    """:func:`timed` of each of ``fns``, their runs interleaved (one of each per round: the same load for all)."""
    for fn in fns:
        fn()
    walls: list[list[float]] = [[] for _ in fns]
    cpus: list[list[float]] = [[] for _ in fns]
    for _ in range(runs):
        for i, fn in enumerate(fns):
            c0, t0 = _children_cpu_s(), time.perf_counter()
            fn()
            walls[i].append(time.perf_counter() - t0)
            cpus[i].append(_children_cpu_s() - c0)
    return [(statistics.median(w), min(w), statistics.median(c)) for w, c in zip(walls, cpus, strict=True)]


def _python(code: str) -> Callable[[], object]:
    return lambda: subprocess.run([sys.executable, "-c", code], env=HEADLESS, check=True, capture_output=True)


def _solve(env: dict[str, str], out: Path) -> Callable[[], object]:
    argv = [sys.executable, "-m", "ur3hanoi", "solve", "--start", "1", "--end", "2", "--blocks", "1", "--fps", "2",
            "--size", "64x48", "--video", str(out)]

    def run() -> None:
        proc = subprocess.run(argv, env=env, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            raise SystemExit(f"solve --video failed: {proc.stderr}")

    return run


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=5)
    runs = parser.parse_args().runs
    chosen = choose(HEADLESS)
    print(f"machine: {os.cpu_count()} cores, load {os.getloadavg()[0]:.2f}; chosen without a display: "
          f"{chosen.describe()}; {runs} runs each (median, best wall; median CPU)")
    rows = [
        ("python -c pass (the floor)", timed(_python("pass"), runs)),
        ("python -c 'import mujoco'", timed(_python("import mujoco"), runs)),
        (f"one probe ({chosen.platform.name})", timed(lambda: probe(chosen.platform.name, HEADLESS), runs)),
        ("the choice, MUJOCO_GL unset, no display", timed(lambda: choose(HEADLESS), runs)),
    ]
    with tempfile.TemporaryDirectory(prefix="ur3hanoi-bench-opengl-") as tmp:
        out = Path(tmp) / "run.mp4"
        verified = {**HEADLESS, MUJOCO_GL: chosen.platform.name, VERIFIED: f"{chosen.platform.name} set"}
        base, probed = interleaved([_solve(verified, out), _solve(HEADLESS, out)], runs)
        rows.append(("solve --video, MUJOCO_GL set by hand (baseline)", base))
        rows.append(("solve --video, MUJOCO_GL unset (probes)", probed))
    for name, (wall, best, cpu) in rows:
        print(f"  {name:<50} {wall:6.2f} s wall (best {best:5.2f}), {cpu:5.2f} s CPU")
    base, probed = rows[-2][1], rows[-1][1]
    print(f"  the probe's share of a short solve --video: +{probed[0] - base[0]:.2f} s wall, "
          f"+{probed[2] - base[2]:.2f} s CPU; load now {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
