#!/usr/bin/env python3
"""Benchmark the plan on the official UR drivers' interface in real time, ROS 1 and ROS 2, against the baselines a
user would otherwise run, on the same machine.

Usage: .venv/bin/python bench/bench_driver.py [--only ros1|ros2|cycle]
Needs Debian's ROS 1 (tools/ensure-system-deps.sh) and, for ROS 2, ``unshare -n`` and the Jazzy rclpy environment of
``ur3hanoi ros2-env`` (built once in the user cache: minutes on a first run). About 10 minutes on the wall clock.

Measures, each run against a fresh station (tower 1 -> 3):
- the driver solves: ``ros-solve --driver ur`` on ``ros-station --driver ur`` (its own roscore on a free port;
  lab_sim, 125 Hz) and ``ros2-solve --driver ur`` on ``ros2-station --driver ur`` (rclpy, inside a private network
  namespace: ur3e_sim at its 500 Hz, lab_sim at 125 Hz), 3 blocks at speed scaling 1 and 0.5: the client's executed
  time against the plan's own cycle time, every block in place (the station's report), the path the client measured
  (the largest distance of the executed suction point from the plan's path, and on the vertical legs; the joint
  states it received per second), the station's loop (mean and worst lag of a cycle's start behind its schedule,
  cycles more than one period late);
- the halt: one block dropped during its carry (``--drop-on-grasp 1``): control cycles (and milliseconds) from the
  first ``io_states`` without the block to the cancel's arrival at the station (its report's ``halts``);
- the baselines: ``ros-solve`` through ``ur3/command`` on ``ros-station`` (the course interface) and ``ros2-solve``
  through ``ur3e/command`` on ``ros2-station`` in its bridge timing (every command a fixed 2 s, as the course's
  UR3e bridge): their wall time, commands, blocks;
- one control cycle on the CPU clock (median over a 1-block loopback solve: the station core without middleware,
  cycles back to back) and at the control rate with each middleware's publishing step (median over 3 s of idle
  cycles, a client subscribed) [us], wall and thread CPU time (a loop that sleeps between cycles finds its caches
  cold when other programs ran meanwhile).
Prints the load average beside the figures: the stations are Python loops and share the machine's cores.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import socket
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

TIMEOUT_S = 600.0
PRELUDE = """set -u
ip link set lo up && ip link set lo multicast on
wait_ready() {
  for _ in $(seq 1 300); do grep -q "ros2-station: ready" "$1" && return 0; sleep 0.2; done
  echo "station not ready" >&2; cat "$1" >&2; return 1
}
"""


@dataclass
class Run:
    """One station and one client: the client's exit code and JSON outcome, the station's report."""

    label: str
    code: int
    outcome: dict[str, Any]
    report: dict[str, Any]
    calibration: str = "lab_sim"
    load: float = field(default_factory=lambda: os.getloadavg()[0])

    def blocks(self) -> list[tuple[int, int | None, int | None]]:
        return [(b["block"], b["tower"], b["height"]) for b in self.report.get("final", {}).get("blocks", [])]

    def in_place(self, n: int) -> bool:
        return sorted(self.blocks()) == [(b, 3, b) for b in range(1, n + 1)]


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "ur3hanoi.cli", *args]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _outcome(stdout: str, stderr: str) -> dict[str, Any]:
    lines = stdout.strip().splitlines()
    try:
        return dict(json.loads(lines[-1]))
    except (IndexError, json.JSONDecodeError):
        return {"error": (stderr.strip().splitlines() or ["no output"])[-1]}


# ------------------------------------------------------------------------------------------------------ ROS 1
@contextmanager
def ros1_env(tmp: Path) -> Iterator[dict[str, str]]:
    """A roscore of its own on a free port; the environment to reach it."""
    from ur3hanoi.interface.ros1.master import RosCore

    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(tmp / "ros_home"),
               ROS_IP="127.0.0.1", PYTHONUNBUFFERED="1")
    (tmp / "ros_home").mkdir(exist_ok=True)
    os.environ.update(ROS_HOME=env["ROS_HOME"], ROS_IP="127.0.0.1")
    with RosCore(env["ROS_MASTER_URI"]):
        yield env


def ros1_run(tmp: Path, label: str, station: list[str], solve: list[str]) -> Run:
    """``ros-station STATION`` (report to a file), then ``ros-solve SOLVE --json`` against it."""
    report = tmp / "report.json"
    report.unlink(missing_ok=True)
    with ros1_env(tmp) as env:
        proc = subprocess.Popen(cli("ros-station", *station, "--report", str(report)), env=env, text=True,
                                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
        try:
            assert proc.stderr is not None
            for line in proc.stderr:
                if line.startswith("ur3hanoi ros-station: ready"):
                    break
            else:
                raise RuntimeError(f"ros-station {' '.join(station)} exited before it was ready")
            result = subprocess.run(cli("ros-solve", "--start", "1", "--end", "3", "--json", *solve), env=env,
                                    text=True, capture_output=True, timeout=TIMEOUT_S)
            proc.send_signal(signal.SIGINT)
            proc.wait(timeout=60)
        finally:
            if proc.poll() is None:
                os.killpg(proc.pid, signal.SIGKILL)
                proc.wait()
    return Run(label, result.returncode, _outcome(result.stdout, result.stderr), json.loads(report.read_text()))


# ------------------------------------------------------------------------------------------------------ ROS 2
def rclpy_prefix() -> str:
    """``env VAR=...`` of the Jazzy rclpy environment (built once in the user cache)."""
    from ur3hanoi.interface.ros2.rclpy_build import WHEELS, ensure_env
    from ur3hanoi.io.cache import cache_dir

    env = ensure_env(cache_dir(), WHEELS["jazzy"], sys.executable,
                     log=lambda m: print(f"# ros2-env: {m}", file=sys.stderr, flush=True))
    return "env " + " ".join(f"{k}={shlex.quote(v)}" for k, v in env.variables("jazzy").items())


def ros2_run(tmp: Path, label: str, prefix: str, station: str, solve: str, calibration: str) -> Run:
    """``ros2-station STATION`` and ``ros2-solve SOLVE --json`` in one private network namespace."""
    ur3hanoi = f"{prefix} {shlex.quote(sys.executable)} -m ur3hanoi.cli"
    script = f"""{PRELUDE}
{ur3hanoi} ros2-station {station} --report {tmp}/report.json > {tmp}/st.out 2> {tmp}/st.err &
ST=$!
wait_ready {tmp}/st.err || exit 90
{ur3hanoi} ros2-solve --start 1 --end 3 --json {solve} > {tmp}/solve.out 2> {tmp}/solve.err
echo $? > {tmp}/solve.code
kill -INT $ST; wait $ST
"""
    for name in ("report.json", "solve.code", "solve.out", "solve.err"):
        (tmp / name).unlink(missing_ok=True)
    subprocess.run(["unshare", "-n", "bash", "-c", script], cwd=REPO, timeout=TIMEOUT_S, check=False,
                   env=dict(os.environ, PYTHONUNBUFFERED="1", ROS_DOMAIN_ID="0"))
    if not (tmp / "solve.code").exists():
        raise RuntimeError(f"ros2-station {station}: {(tmp / 'st.err').read_text().strip()[-300:]}")
    outcome = _outcome((tmp / "solve.out").read_text(), (tmp / "solve.err").read_text())
    return Run(label, int((tmp / "solve.code").read_text()), outcome, json.loads((tmp / "report.json").read_text()),
               calibration)


# ------------------------------------------------------------------------------------------------------ rows
def loop_text(report: dict[str, Any]) -> str:
    c = report["control"]
    return (f"{1e3 * c['mean_lag_s']:.2f} / {1e3 * c['worst_lag_s']:.1f}".rjust(13)
            + f"{c['late_cycles']:>7}/{c['cycles']}")


def plan_at(calibration: str, slider: float) -> tuple[float, float]:
    """The plan's own cycle time [s] and its time at ``slider``: the motion slowed, the dwells as they are."""
    from ur3hanoi.plan import PlanConfig, plan_solve
    from ur3hanoi.station.calibration import load_station

    plan = plan_solve(load_station(calibration), 0, 2, 3, PlanConfig())
    return plan.duration_s, plan.motion_s / slider + plan.dwell_total_s


def driver_row(r: Run, n: int) -> str:
    o, rate = r.outcome, r.report["control"]["rate_hz"]
    head = f"{r.label:<28}{rate:>5g}"
    if r.code != 0:
        return f"{head}  exit {r.code}: {o.get('error', o)}"
    ex = o["executed_s"]
    own, at_slider = plan_at(r.calibration, r.report["driver"]["speed_slider"])
    vertical = o.get("vertical_path_deviation_mm")
    js = o.get("joint_states_measured", 0) / ex if ex > 0 else 0.0
    return (f"{head}{ex:>9.2f}{own:>8.2f}{at_slider:>9.2f}{ex / at_slider:>7.3f}  {'yes' if r.in_place(n) else 'NO':<6}"
            f"{o.get('path_deviation_mm', float('nan')):>7.3f}{'-' if vertical is None else f'{vertical:.3f}':>7}"
            f"{js:>6.0f} {loop_text(r.report)}  {r.load:>4.1f}")


DRIVER_HEAD = (f"{'':<28}{'':>5}{'executed':>9}{'plan':>8}{'plan at':>9}{'':>7}  {'blocks':<6}{'path':>7}"
               f"{'vert.':>7}{'joint':>6} {'loop lag':>13}{'late':>7}\n"
               f"{'station, slider':<28}{'Hz':>5}{'[s]':>9}{'[s]':>8}{'slider':>9}{'ratio':>7}  {'placed':<6}"
               f"{'[mm]':>7}{'[mm]':>7}{'st/s':>6} {'mean/worst ms':>13}{'cycles':>7}  load")


def halt_row(r: Run) -> str:
    halts = r.report.get("halts", [])
    figure = ", ".join(f"{h['cycles']} cycle{'s' if h['cycles'] != 1 else ''} ({h['wall_ms']:.1f} ms)"
                       for h in halts) or "none recorded"
    period = 1e3 / r.report["control"]["rate_hz"]
    return (f"{r.label:<34} exit {r.code}; feedback lost -> cancel at the station: {figure}; one cycle = "
            f"{period:g} ms; load {r.load:.1f}")


def baseline_row(r: Run, n: int) -> str:
    o = r.outcome
    if r.code != 0:
        return f"{r.label:<66} exit {r.code}: {o.get('error', o)}"
    commands = r.report.get("commands", {}).get("executed", "?")
    return (f"{r.label:<66}{o['wall_time_s']:>8.1f} s, {commands} commands, blocks in place: "
            f"{'yes' if r.in_place(n) else 'NO'}; load {r.load:.1f}")


# ------------------------------------------------------------------------------------------------------ cycle
CORE_CODE = """
import gc, sys, time
import numpy as np
from ur3hanoi.interface.urdriver.station import DriverStation, DriverStationOptions
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport
from ur3hanoi.interface.urdriver.solve import run_driver_solve
from ur3hanoi.plan import PlanConfig, plan_solve
st = DriverStation(DriverStationOptions(calibration=sys.argv[1], n_blocks=1), lambda s: None, lambda s: None)
plan = plan_solve(st.station, 0, 2, 1, PlanConfig())
cycle, times = st.cycle, []
def timed():
    c0, t0 = time.thread_time(), time.perf_counter(); cycle()
    times.append((time.perf_counter() - t0, time.thread_time() - c0))
st.cycle = timed
tr = LoopbackTransport(st); tr.connect()
gc.collect()
run_driver_solve(tr, plan, st.station.wiring)
wall, cpu = np.median(np.array(times), axis=0)
print(f"{1e6 * wall:.0f} {1e6 * cpu:.0f} {len(times)}")
"""
MEASURE_CODE = """
import time
import numpy as np
def measure(cycle, publish, rate):  # 3 s at rate: median wall and thread CPU [us] of the core and of publishing
    period, tt, pc = 1.0 / rate, time.thread_time, time.perf_counter
    rows = []
    for _ in range(int(3 * rate)):
        c0, w0 = tt(), pc(); cycle(); c1, w1 = tt(), pc(); publish(); c2, w2 = tt(), pc()
        rows.append((w1 - w0, c1 - c0, w2 - w1, c2 - c1)); time.sleep(max(0.0, period - (w2 - w0)))
    return [round(1e6 * x) for x in np.median(np.array(rows), axis=0)]
"""
ROS1_PUBLISH_CODE = MEASURE_CODE + """
import subprocess, sys
sys.setswitchinterval(0.0005)  # as ros-station's loop sets it (ur3hanoi.interface.ros1.server)
from ur3hanoi.interface.ros1.env import import_rospy
from ur3hanoi.interface.ros1.ur_server import RosDriverOptions, RosDriverServer
rospy = import_rospy()
st = RosDriverServer(RosDriverOptions(n_blocks=1), out=lambda s: None, report_out=lambda s: None)
rospy.init_node("bench_station", disable_signals=True)
publish = st._open(rospy)
client = subprocess.Popen([sys.executable, "-c", sys.argv[1]], stdout=subprocess.PIPE, text=True)
import selectors
sel = selectors.DefaultSelector(); sel.register(client.stdout, selectors.EVENT_READ)
end = time.monotonic() + 60
while time.monotonic() < end:  # serve until the client is connected
    st.cycle(); publish()
    if sel.select(timeout=0.008):
        break
print(*measure(st.cycle, publish, 125.0))
client.kill(); client.wait()
rospy.signal_shutdown("done")
"""
ROS1_CLIENT_CODE = """
import os, time
from ur3hanoi.interface.ros1.ur_client import RosDriverTransport
t = RosDriverTransport(os.environ["ROS_MASTER_URI"], 60.0); t.connect()
print("connected", flush=True)
time.sleep(60)
"""
ROS2_PUBLISH_CODE = MEASURE_CODE + """
import subprocess, sys
from ur3hanoi.interface.ros2.ur_station import Ros2DriverOptions, Ros2DriverStation
from ur3hanoi.interface.ros2.ur_node import DriverNode
cal, rate = sys.argv[1], float(sys.argv[2])
st = Ros2DriverStation(Ros2DriverOptions(calibration=cal, n_blocks=1, rate_hz=rate), out=lambda s: None,
                       log=lambda s: None)
node = DriverNode(st, "jazzy", None)
period = 1.0 / rate
client = subprocess.Popen([sys.executable, "-c", sys.argv[3]], stdout=subprocess.PIPE, text=True)
import selectors
sel = selectors.DefaultSelector(); sel.register(client.stdout, selectors.EVENT_READ)
end = time.monotonic() + 60
while time.monotonic() < end:  # serve until the client is connected
    st.cycle(); node.publish()
    if sel.select(timeout=period):
        break
print(*measure(st.cycle, node.publish, rate))
client.kill(); client.wait(); node.close()
"""
ROS2_CLIENT_CODE = """
import time
from ur3hanoi.interface.ros2.ur_client import RclpyDriverTransport
t = RclpyDriverTransport("jazzy", connect_timeout_s=60.0); t.connect()
print("connected", flush=True)
time.sleep(60)
"""


def _binding_line(what: str, middleware: str, out: subprocess.CompletedProcess[str]) -> str:
    figures = out.stdout.split()
    if len(figures) != 4:
        return f"{what}: failed: {out.stderr.strip()[-300:]}"
    core_wall, core_cpu, pub_wall, pub_cpu = figures
    return (f"{what}, idle, a client subscribed: core {core_wall} us ({core_cpu} us CPU) + {middleware} publishing "
            f"{pub_wall} us ({pub_cpu} us CPU) per cycle")


def cycle_lines(prefix: str | None, ros1: bool) -> list[str]:
    """The cost of one control cycle [us] (see the module docstring)."""
    lines = []
    for cal, hz in (("lab_sim", 125), ("ur3e_sim", 500)):
        out = subprocess.run([sys.executable, "-c", CORE_CODE, cal], cwd=REPO, capture_output=True, text=True,
                             timeout=TIMEOUT_S)
        figures = out.stdout.split()
        if len(figures) != 3:
            lines.append(f"station core, {cal}: failed: {out.stderr.strip()[-300:]}")
            continue
        wall, cpu, n = figures
        lines.append(f"station core, {cal} {hz} Hz, a 1-block solve on the CPU clock ({n} cycles, back to back): "
                     f"{wall} us per cycle ({cpu} us CPU), {float(wall) / (1e4 / hz):.0f} % of the period")
    if ros1:
        with tempfile.TemporaryDirectory(prefix="bench_driver-") as d, ros1_env(Path(d)) as env:
            out = subprocess.run([sys.executable, "-c", ROS1_PUBLISH_CODE, ROS1_CLIENT_CODE], cwd=REPO, env=env,
                                 capture_output=True, text=True, timeout=TIMEOUT_S)
        lines.append(_binding_line("ros-station --driver ur, lab_sim 125 Hz", "rospy", out))
    if prefix is not None:
        for cal, hz in (("lab_sim", 125), ("ur3e_sim", 500)):
            code = " ".join(shlex.quote(x) for x in (sys.executable, "-c", ROS2_PUBLISH_CODE, cal, str(hz),
                                                      ROS2_CLIENT_CODE))
            script = f"{PRELUDE}\nexport ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST\n{prefix} {code}\n"
            out = subprocess.run(["unshare", "-n", "bash", "-c", script], cwd=REPO, capture_output=True, text=True,
                                 timeout=TIMEOUT_S)
            lines.append(_binding_line(f"ros2-station --driver ur, {cal} {hz} Hz", "rclpy", out))
    return lines


# ------------------------------------------------------------------------------------------------------ main
def ros1_runs(tmp: Path) -> tuple[list[Run], list[Run], list[Run]]:
    drivers = [ros1_run(tmp, f"ROS 1 lab_sim, slider {s:g}", ["--driver", "ur", "--speed-scaling", f"{s:g}"],
                        ["--driver", "ur"]) for s in (1.0, 0.5)]
    halt = ros1_run(tmp, "ROS 1 lab_sim 125 Hz", ["--driver", "ur", "--blocks", "1", "--drop-on-grasp", "1"],
                    ["--driver", "ur", "--blocks", "1"])
    course = ros1_run(tmp, "ROS 1 ros-solve via ur3/command on ros-station (lab_sim)", [], [])
    return drivers, [halt], [course]


def ros2_runs(tmp: Path, prefix: str) -> tuple[list[Run], list[Run], list[Run]]:
    drivers, halts = [], []
    for cal, hz in (("ur3e_sim", 500), ("lab_sim", 125)):
        common = f"--driver ur --calibration {cal} --rate {hz}"
        for s in (1.0, 0.5):
            drivers.append(ros2_run(tmp, f"ROS 2 {cal}, slider {s:g}", prefix, f"{common} --speed-scaling {s:g}",
                                    f"--driver ur --calibration {cal}", cal))
        halts.append(ros2_run(tmp, f"ROS 2 {cal} {hz} Hz", prefix, f"{common} --blocks 1 --drop-on-grasp 1",
                              f"--driver ur --calibration {cal} --blocks 1", cal))
    course = ros2_run(tmp, "ROS 2 ros2-solve via ur3e/command on ros2-station (bridge, 2 s)", prefix,
                      "--calibration ur3e_sim --timing bridge", "--calibration ur3e_sim", "ur3e_sim")
    return drivers, halts, [course]


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", choices=("ros1", "ros2", "cycle"), help="run only this part")
    args = ap.parse_args()
    print(f"The plan on the official UR drivers' interface: 3 blocks, tower 1 -> 3; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores at the start")
    prefix = rclpy_prefix() if args.only in (None, "ros2", "cycle") else None
    drivers: list[Run] = []
    halts: list[Run] = []
    baselines: list[Run] = []
    with tempfile.TemporaryDirectory(prefix="bench_driver-") as name:
        tmp = Path(name)
        if args.only in (None, "ros1"):
            for into, runs in zip((drivers, halts, baselines), ros1_runs(tmp), strict=True):
                into += runs
        if args.only in (None, "ros2") and prefix is not None:
            for into, runs in zip((drivers, halts, baselines), ros2_runs(tmp, prefix), strict=True):
                into += runs
    if drivers:
        print("\nThe driver solves (ros-solve / ros2-solve --driver ur): executed time vs the plan's own cycle time, "
              "blocks in place, the path the client measured, the station's loop")
        print(DRIVER_HEAD)
        for r in drivers:
            print(driver_row(r, 3))
    if halts:
        print("\nThe halt: 1 block dropped during its carry (--drop-on-grasp 1)")
        for r in halts:
            print(halt_row(r))
    if baselines:
        print("\nThe baselines (what a user would otherwise run): the course interfaces, the same moves")
        for r in baselines:
            print(baseline_row(r, 3))
    if args.only in (None, "cycle"):
        print("\nOne control cycle (median)")
        for line in cycle_lines(prefix, args.only is None or args.only == "cycle"):
            print(line)
    print(f"(measured {time.strftime('%Y-%m-%d %H:%M')}; load average {os.getloadavg()[0]:.1f} at the end)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
