#!/usr/bin/env python3
"""Benchmark the plan on the UR ROS 2 driver's interface in real time: ``ur3hanoi ros2-solve --driver ur`` against
``ur3hanoi ros2-station --driver ur`` (rclpy from ``ur3hanoi ros2-env``'s Jazzy environment, built once in the user
cache), everything inside a private network namespace (``unshare -n``: no DDS packet leaves the machine).

Usage: .venv/bin/python bench/bench_ros2_driver.py [--calibration ur3e_sim] [--rate HZ]
Measures, each against a fresh station (tower 1 -> 3, the robot's control rate unless --rate):
- a 3-block solve at speed scaling 1 and 0.5: the client's executed time against the plan's own cycle time, the
  blocks' final places, the goals (accepted, succeeded, aborted), the station's loop (mean and worst lag behind its
  wall-clock schedule, publishing rate);
- the halt: one block dropped during its carry (``--drop-on-grasp 1``): control cycles (and milliseconds) from the
  first ``io_states`` without the block to the cancel's arrival at the station;
- the cost of one control cycle on the CPU clock: the station core's cycle and the rclpy publishing step [us].
Prints the load average beside the figures: the station is a Python loop and shares the machine's cores.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from ur3hanoi.interface.ros2.rclpy_build import WHEELS, ensure_env  # noqa: E402
from ur3hanoi.io.cache import cache_dir  # noqa: E402

PRELUDE = """set -u
ip link set lo up && ip link set lo multicast on
"""


def env_prefix() -> str:
    env = ensure_env(cache_dir(), WHEELS["jazzy"], sys.executable,
                     log=lambda m: print(f"# ros2-env: {m}", file=sys.stderr, flush=True))
    return "env " + " ".join(f"{k}={shlex.quote(v)}" for k, v in env.variables("jazzy").items())


def run(prefix: str, tmp: Path, station_args: str, solve_args: str) -> tuple[dict[str, Any], dict[str, Any], int]:
    """One station and one solve in a private network namespace: (solve's JSON outcome, station report, solve code)."""
    ur3hanoi = f"{prefix} {shlex.quote(sys.executable)} -m ur3hanoi.cli"
    script = f"""{PRELUDE}
{ur3hanoi} ros2-station --driver ur {station_args} --report {tmp}/report.json > {tmp}/st.out 2> {tmp}/st.err &
ST=$!
for _ in $(seq 1 300); do grep -q "ros2-station: ready" {tmp}/st.out && break; sleep 0.2; done
{ur3hanoi} ros2-solve --driver ur --start 1 --end 3 --json {solve_args} > {tmp}/solve.json 2> {tmp}/solve.err
echo $? > {tmp}/solve.code
kill -INT $ST; wait $ST
"""
    subprocess.run(["unshare", "-n", "bash", "-c", script], cwd=REPO, timeout=600, check=False,
                   env=dict(os.environ, PYTHONUNBUFFERED="1"))
    code = int((tmp / "solve.code").read_text())
    lines = (tmp / "solve.json").read_text().strip().splitlines()
    outcome = json.loads(lines[-1]) if lines else {"error": (tmp / "solve.err").read_text().strip()}
    return outcome, json.loads((tmp / "report.json").read_text()), code


def loop_line(report: dict[str, Any]) -> str:
    c = report["control"]
    return (f"loop {c['rate_hz']:g} Hz: mean lag {1e3 * c['mean_lag_s']:.1f} ms, worst "
            f"{1e3 * c['worst_lag_s']:.1f} ms, {c['late_cycles']} of {c['cycles']} cycles late, published at "
            f"{c['publish_rate_hz']:.1f} Hz")


def cycle_cost(calibration: str) -> str:
    """Station cycle and rclpy publish step on the CPU clock [us per cycle], in a private network namespace."""
    code = f"""
import time
from ur3hanoi.interface.ros2.ur_station import Ros2DriverOptions, Ros2DriverStation
from ur3hanoi.interface.ros2.ur_node import DriverNode
st = Ros2DriverStation(Ros2DriverOptions(calibration={calibration!r}, n_blocks=3), out=lambda s: None,
                       log=lambda s: None)
node = DriverNode(st, "jazzy", None)
for _ in range(200):
    st.cycle(); node.publish()
t0 = time.perf_counter()
for _ in range(2000):
    st.cycle()
t1 = time.perf_counter()
for _ in range(2000):
    node.publish()
t2 = time.perf_counter()
node.close()
print(f"one control cycle: station core {{(t1 - t0) / 2e-3:.0f}} us, rclpy publishing {{(t2 - t1) / 2e-3:.0f}} us")
"""
    script = (f"{PRELUDE}\nexport ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST\n{env_prefix()} "
              f"{shlex.quote(sys.executable)} -c {shlex.quote(code)}\n")
    out = subprocess.run(["unshare", "-n", "bash", "-c", script], cwd=REPO, capture_output=True, text=True,
                         timeout=300, check=False)
    return out.stdout.strip() or out.stderr.strip()[-300:]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--calibration", default="ur3e_sim")
    p.add_argument("--rate", type=float, default=None)
    args = p.parse_args()
    prefix = env_prefix()
    rate = "" if args.rate is None else f" --rate {args.rate:g}"
    common = f"--calibration {args.calibration}{rate}"
    print(f"ros2-station --driver ur / ros2-solve --driver ur ({args.calibration}, Jazzy wheels), load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    for scaling in (1.0, 0.5):
        with tempfile.TemporaryDirectory() as d:
            outcome, report, code = run(prefix, Path(d), f"{common} --speed-scaling {scaling:g}",
                                        f"--calibration {args.calibration}")
        blocks = [(b["block"], b["tower"], b["height"]) for b in report["final"]["blocks"]]
        solved = code == 0 and all(t == 3 for _, t, _ in blocks)
        if code == 0:
            figure = (f"executed {outcome['executed_s']:.2f} s vs the plan's {outcome['plan_duration_s']:.2f} s "
                      f"({outcome['executed_s'] / outcome['plan_duration_s']:.3f}x)")
        else:
            figure = f"exit {code}: {outcome.get('error', outcome)}"
        g = report["goals"]
        print(f"3 blocks, speed scaling {scaling:g}: {figure}; {'solved' if solved else 'NOT solved'} {blocks}; "
              f"goals {g['accepted']} accepted, {g['succeeded']} succeeded, {g['aborted']} aborted, {g['canceled']} "
              f"canceled; {loop_line(report)}; load {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as d:
        outcome, report, code = run(prefix, Path(d), f"{common} --blocks 1 --drop-on-grasp 1",
                                    f"--calibration {args.calibration} --blocks 1")
    halts = report["halts"]
    figure = ", ".join(f"{h['cycles']} cycles ({h['wall_ms']} ms)" for h in halts) or "none recorded"
    print(f"halt (block dropped in the carry): exit {code}; feedback lost -> cancel at the station: {figure}; "
          f"{loop_line(report)}")
    print(cycle_cost(args.calibration))
    print(f"(measured {time.strftime('%Y-%m-%d %H:%M')})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
