#!/usr/bin/env python3
"""Benchmark the ROS bridge in real time: a full 3-block solve through ur3/command against `ur3hanoi ros-station`.

Usage: .venv/bin/python bench/bench_ros.py [--v V] [--a A]
Measures, each against a fresh station (own roscore on a free port, tower 1 -> 3):
- `ur3hanoi ros-solve` wall time (the client's own figure: first command to home),
- the lab-style client tests/support/lab2_exec_starter.py (written like the course's lab2_exec.py: 20 Hz polling, 1 s
  sleep
  after every grasp) wall time, run with `ur3hanoi ros-env`'s environment,
- the station's control loop: worst and mean lag of a cycle's start behind its wall-clock schedule, cycles more than
  one period late, publishing rate; and how the arm settled (worst time from a profile's end to within 0.0005 rad,
  worst error at rest).
With --flood S: instead, a publisher floods ur3/command with valid commands at 1 kHz for S seconds (twice: S/4
and S, to show what grows with the number of commands) while subscribing ur3/position. Measures the largest gap
between received positions, the station's late cycles (more than one period) and worst lag, its stderr lines
per second, the report's size, and its resident memory growth per command (VmRSS before and after the flood),
extrapolated to an hour of flooding.
Needs Debian's ROS 1 (tools/ensure-system-deps.sh). ROS runs on the wall clock: about 2 minutes.
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
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
SUPPORT = REPO / "tests" / "support"
sys.path.insert(0, str(REPO))

from ur3hanoi.interface.ros1.master import RosCore  # noqa: E402

TIMEOUT_S = 300.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "ur3hanoi.cli", *args]


def run_against_station(tmp: Path, client: list[str], stdin: str | None = None) -> tuple[float, dict[str, Any]]:
    """Start roscore + ros-station, run ``client`` to completion; returns (client wall time [s], station report)."""
    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(tmp / "ros_home"),
               ROS_IP="127.0.0.1", PYTHONUNBUFFERED="1")
    os.environ.update(ROS_HOME=env["ROS_HOME"], ROS_IP="127.0.0.1")
    report = tmp / f"report-{port}.json"
    with RosCore(env["ROS_MASTER_URI"]):
        station = subprocess.Popen(cli("ros-station", "--report", str(report)), env=env, text=True,
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True)
        try:
            assert station.stderr is not None
            for line in station.stderr:  # the ready line (stderr: stdout carries only a report)
                if line.startswith("ur3hanoi ros-station: ready"):
                    break
            else:
                raise AssertionError("ros-station exited before it was ready")
            t0 = time.perf_counter()
            result = subprocess.run(client, env=env, input=stdin, text=True, capture_output=True, timeout=TIMEOUT_S)
            wall = time.perf_counter() - t0
            assert result.returncode == 0, result.stdout + result.stderr
            station.send_signal(signal.SIGINT)
            station.wait(timeout=30)
        finally:
            if station.poll() is None:
                os.killpg(station.pid, signal.SIGKILL)
                station.wait()
    data = json.loads(report.read_text())
    slots = {b["block"]: (b["tower"], b["height"]) for b in data["final"]["blocks"]}
    assert slots == {1: (3, 1), 2: (3, 2), 3: (3, 3)}, slots
    return wall, data


def rss_kb(pid: int) -> int:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    return 0


def flood_once(tmp: Path, seconds: float) -> dict[str, Any]:
    """One station, one 1 kHz flood of ``seconds``; the figures of the module docstring."""
    from ur3hanoi.station.calibration import load_station

    port = free_port()
    env = dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(tmp / "ros_home"),
               ROS_IP="127.0.0.1", PYTHONUNBUFFERED="1")
    os.environ.update(ROS_HOME=env["ROS_HOME"], ROS_IP="127.0.0.1")
    home = [round(x, 12) for x in load_station("lab_sim").q_home]
    # The lab's re-publish of the pose it is at, suction toggled: every command is valid and runs at once (one
    # per control period), so the bounded records fill within a second and what grows after that is measured.
    fields = [{"destination": home, "v": 4.0, "a": 4.0, "io_0": True},
              {"destination": home, "v": 4.0, "a": 4.0, "io_0": False}]
    report = tmp / f"report-{port}.json"
    errlog = tmp / f"stderr-{port}.txt"
    with RosCore(env["ROS_MASTER_URI"]), open(errlog, "w+") as err:
        station = subprocess.Popen(cli("ros-station", "--report", str(report)), env=env, text=True,
                                   stdout=err, stderr=err, start_new_session=True)
        try:
            deadline = time.monotonic() + 120
            while "ur3hanoi ros-station: ready" not in errlog.read_text():
                assert station.poll() is None and time.monotonic() < deadline, errlog.read_text()
                time.sleep(0.1)
            time.sleep(1.0)
            lines0 = len(errlog.read_text().splitlines())
            publisher = subprocess.Popen([sys.executable, str(SUPPORT / "ros_publisher.py"), "--flood", "1000",
                                          str(seconds), json.dumps(fields)], env=env, stdout=subprocess.PIPE,
                                         stderr=subprocess.PIPE, text=True)
            samples = []  # (time [s], VmRSS [kB]) every 0.25 s while the publisher runs
            while publisher.poll() is None:
                samples.append((time.monotonic(), rss_kb(station.pid)))
                time.sleep(0.25)
            out, errs = publisher.communicate()
            result = subprocess.CompletedProcess(publisher.args, publisher.returncode, out, errs)
            assert result.returncode == 0, result.stderr
            lines1 = len(errlog.read_text().splitlines())
            station.send_signal(signal.SIGINT)
            station.wait(timeout=30)
        finally:
            if station.poll() is None:
                os.killpg(station.pid, signal.SIGKILL)
                station.wait()
    flood = json.loads(result.stdout.splitlines()[-1])
    data = json.loads(report.read_text())
    c, ctl = data["commands"], data["control"]
    received = c["executed"] + c["rejected"] + c["queued"]
    # Growth per command after warm-up: the slope of VmRSS over the second half of the flood (the first half fills
    # the bounded records and rospy's buffers), at the measured command rate.
    half = [(t, kb) for t, kb in samples if t >= samples[-1][0] - 0.5 * seconds]
    slope_kb_s = (half[-1][1] - half[0][1]) / max(1e-9, half[-1][0] - half[0][0]) if len(half) > 1 else 0.0
    rss0, rss1 = samples[0][1], samples[-1][1]
    return {"seconds": seconds, "sent": flood["sent"], "received": received, "executed": c["executed"],
            "positions": flood["positions"],
            "max_gap_ms": 1e3 * flood["max_gap_s"], "late": ctl["late_cycles"],
            "worst_lag_ms": 1e3 * ctl["worst_lag_s"],
            "lines_per_s": (lines1 - lines0) / flood["seconds"], "report_bytes": report.stat().st_size,
            "rss_growth_kb": rss1 - rss0, "bytes_per_cmd": 1024.0 * slope_kb_s / (received / flood["seconds"])}


def main_flood(seconds: float) -> int:
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_ros-") as name:
        tmp = Path(name)
        (tmp / "ros_home").mkdir()
        for s in (seconds / 4.0, seconds):
            rows.append(flood_once(tmp, s))
    print("ur3/command flood at 1 kHz (valid: the pose the arm is at, suction toggled) against ur3hanoi ros-station, "
          f"125 Hz; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs")
    print(f"{'flood [s]':>9} {'sent':>6} {'recv':>6} {'exec':>5} {'positions':>9} {'max pos gap [ms]':>16} {'late':>5} "
          f"{'worst lag [ms]':>14} {'log lines/s':>11} {'report [B]':>10} {'RSS +[kB]':>9} {'B/cmd, 2nd half':>15}")
    for r in rows:
        print(f"{r['seconds']:>9.1f} {r['sent']:>6} {r['received']:>6} {r['executed']:>5} {r['positions']:>9} "
              f"{r['max_gap_ms']:>16.1f} "
              f"{r['late']:>5} {r['worst_lag_ms']:>14.1f} {r['lines_per_s']:>11.2f} {r['report_bytes']:>10} "
              f"{r['rss_growth_kb']:>9} {r['bytes_per_cmd']:>15.1f}")
    last = rows[-1]
    print(f"extrapolated to one hour at 1 kHz: {last['bytes_per_cmd'] * 3.6e6 / 2**20:.1f} MiB of memory growth "
          f"(second-half RSS slope, allocator noise included), report {rows[0]['report_bytes']} -> "
          f"{last['report_bytes']} bytes for {rows[0]['received']} -> {last['received']} commands")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--v", default="4.0", help="ros-solve joint speed [rad/s] (default 4.0, the lab's)")
    ap.add_argument("--a", default="4.0", help="ros-solve joint acceleration [rad/s^2] (default 4.0, the lab's)")
    ap.add_argument("--flood", type=float, metavar="S", help="instead: flood ur3/command at 1 kHz for S/4 and S s")
    args = ap.parse_args()
    if args.flood:
        return main_flood(args.flood)
    rows = []
    with tempfile.TemporaryDirectory(prefix="bench_ros-") as name:
        tmp = Path(name)
        (tmp / "ros_home").mkdir()
        wall, rep = run_against_station(tmp, cli("ros-solve", "--start", "1", "--end", "3", "--v", args.v,
                                                 "--a", args.a))
        rows.append((f"ur3hanoi ros-solve (v={args.v}, a={args.a})", wall, rep))
        table = tmp / "lab2_data.yaml"
        subprocess.run(cli("tables", "lab_sim", "--key", "sim_pos", "-o", str(table)), check=True,
                       capture_output=True)
        env_cmd = shlex.join(cli("ros-env", "--dir", str(tmp / "ros-env")))
        program = shlex.join([sys.executable, str(SUPPORT / "lab2_exec_starter.py"), "--yaml", str(table)])
        wall, rep = run_against_station(tmp, ["bash", "-c", f'eval "$({env_cmd})" 2>/dev/null && exec {program}'],
                                        stdin="1\n3\n")
        rows.append(("lab-style lab2_exec_starter.py (v=a=4, 1 s grasp sleep)", wall, rep))
    print("3 blocks, tower 1 -> 3, lab_sim, against ur3hanoi ros-station (125 Hz), wall clock")
    print(f"{'client':<58} {'wall [s]':>8} {'cmds':>5} {'worst lag [ms]':>14} {'mean lag [ms]':>13} "
          f"{'late':>5} {'pub [Hz]':>8} {'settle [ms]':>11} {'rest err [rad]':>14}")
    for label, wall, rep in rows:
        c, ctl = rep["commands"], rep["control"]
        # No rest of 0.2 s or more between two commands (a client that sends the next one on arrival): no rest error.
        rest = "-" if c["max_rest_error_rad"] is None else f"{c['max_rest_error_rad']:.2e}"
        print(f"{label:<58} {wall:>8.1f} {c['executed']:>5} {1e3 * ctl['worst_lag_s']:>14.2f} "
              f"{1e3 * ctl['mean_lag_s']:>13.3f} {ctl['late_cycles']:>5} {ctl['publish_rate_hz']:>8.1f} "
              f"{1e3 * c['max_settle_s']:>11.0f} {rest:>14}")
    for label, _wall, rep in rows:
        print(f"loop lag histogram [ms], {label.split(' (')[0]}: {rep['control']['lag_histogram_ms']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
