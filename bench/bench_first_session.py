#!/usr/bin/env python3
"""Benchmark a student's whole first session on a cell that runs only the official UR driver, ROS 1 and ROS 2: from
power-on to a solved tower, no number typed, each step's wall time.

Usage: .venv/bin/python bench/bench_first_session.py [--only ros1|ros2] [--out DIR]
Needs Debian's ROS 1 (tools/ensure-system-deps.sh) and, for ROS 2, ``unshare -n`` and the Jazzy rclpy environment of
``ur3hanoi ros2-env`` (built once in the user cache). About 15 minutes on the wall clock.

The cell is the driver's stand-in (``ros-station --driver ur``; ``ros2-station --driver ur`` at the UR3's 125 Hz in a
private network namespace) on a station set up as a student would (tests/support/student_cell.py: every tower tens of
millimetres from lab_real's place, the row turned); the student starts from ``lab_real`` (the robot, the tool, the
blocks) and their lab file (``lab2_data.yaml`` with the course's ``sim_pos``). The steps, as the real-arm page walks
them:

1. power-on: the driver up (the stand-in's ready line; on the robot: the controller booted, the driver launched);
2. check: ``check-arm --suction`` (the slider at 100 % is warned);
3. teach: ``teach --driver ur`` through its pseudo-terminal, a scripted operator jogging with teach's keys to every
   pose the guidance names, the suction switched on and off on the first contact (``v``), then ``f``;
4. calibrate and the table: what ``f`` does (the calibration fitted and written, ``real_pos`` spliced into the
   student's ``lab2_data.yaml``);
5. solve at 25 %: ``ros-solve --driver ur`` on the written table, tower 1 to 3, the pendant's slider at 25 %;
6. solve at 100 %: back from tower 3 to 1, the slider at 100 %.

The stand-in's slider is set when it starts: moving it (steps 5 and 6) restarts the stand-in, the blocks where the
last step left them and the arm at home; that restart is not counted. Every step's output is kept in ``--out``
(default a temporary folder): the real-arm page shows them. Prints one line per step and the session's total.
"""

from __future__ import annotations

import argparse
import json
import os
import shlex
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

STEP_TIMEOUT_S = 900.0
UR3HANOI = [sys.executable, "-m", "ur3hanoi.cli"]


class Session:
    """One first session on ``via`` (``ros`` or ``ros2``) in ``folder``: its stand-in and steps."""

    def __init__(self, via: str, folder: Path) -> None:
        self.via, self.folder = via, folder
        self.env = dict(os.environ, PYTHONUNBUFFERED="1", ROS_HOME=str(folder), ROS_IP="127.0.0.1")
        self.station: subprocess.Popen[str] | None = None
        self.core: object | None = None
        self.steps: list[tuple[str, float, str]] = []

    # ------------------------------------------------------------------------------------------- the stand-in
    def power_on(self, *args: str) -> float:
        """Start the stand-in with ``args``; the wall time [s] until its ready line."""
        log = self.folder / "station.log"
        t0 = time.perf_counter()
        cmd = [*UR3HANOI, "ros-station" if self.via == "ros" else "ros2-station", "--driver", "ur", "--calibration",
               str(self.folder / "student.yaml"), *args] + ([] if self.via == "ros" else ["--rate", "125"])
        with log.open("w") as out:
            self.station = subprocess.Popen(cmd, env=self.env, stdin=subprocess.DEVNULL, stdout=out,
                                            stderr=subprocess.STDOUT, start_new_session=True, text=True)
        while "ready" not in log.read_text():
            if self.station.poll() is not None or time.perf_counter() - t0 > 120:
                raise SystemExit(f"the stand-in did not start:\n{log.read_text()}")
            time.sleep(0.05)
        return time.perf_counter() - t0

    def power_off(self) -> None:
        st, self.station = self.station, None
        if st is not None and st.poll() is None:
            st.send_signal(signal.SIGINT)
            try:
                st.wait(timeout=30)
            except subprocess.TimeoutExpired:
                os.killpg(st.pid, signal.SIGKILL)
                st.wait()

    # ------------------------------------------------------------------------------------------------ steps
    def run(self, name: str, cmd: list[str]) -> str:
        """Run one step's command; keep its output (stdout then stderr) and wall time."""
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, cwd=self.folder, env=self.env, capture_output=True, text=True,
                              timeout=STEP_TIMEOUT_S)
        wall = time.perf_counter() - t0
        text = proc.stdout + proc.stderr
        (self.folder / f"{name}.txt").write_text(f"$ {shlex.join(['ur3hanoi', *cmd[3:]])}\n{text}")
        if proc.returncode not in (0,):
            raise SystemExit(f"{name} failed (exit {proc.returncode}):\n{text}")
        self.steps.append((name, wall, text))
        return text

    def session(self) -> dict[str, float]:
        from tests.support.student_cell import write_student_station

        f, via = self.folder, self.via
        write_student_station(f / "student.yaml")
        subprocess.run([*UR3HANOI, "tables", "lab_sim", "--key", "sim_pos", "-o", str(f / "lab2_data.yaml")],
                       env=self.env, check=True, capture_output=True)
        times: dict[str, float] = {"power-on": self.power_on()}
        drv = ["--via", via, "--driver", "ur"]
        self.run("check", [*UR3HANOI, "check-arm", *drv, "--calibration", "lab_real", "--suction"])
        times["check"] = self.steps[-1][1]
        out = subprocess.run([sys.executable, "-m", "tests.support.student_cell", str(f), "12", *drv],
                             cwd=REPO, env=self.env, capture_output=True, text=True, timeout=STEP_TIMEOUT_S)
        if out.returncode != 0 or not out.stdout.strip():
            raise SystemExit(f"teach failed:\n{out.stdout}\n{out.stderr}")
        seen = json.loads(out.stdout.strip().splitlines()[-1])
        if seen["exit"] != 0:
            raise SystemExit(f"teach exit {seen['exit']}:\n{(f / 'transcript.txt').read_text()[-3000:]}")
        times["teach"], times["calibrate + table"] = seen["teach_s"], seen["finish_s"]
        times["poses"] = len(seen["poses"])
        solve = "ros-solve" if via == "ros" else "ros2-solve"
        table = ["--table", "lab2_data.yaml", "--key", "real_pos", "--calibration", "station.yaml"]
        self.power_off()
        self.power_on("--speed-scaling", "0.25")
        self.run("solve-25", [*UR3HANOI, solve, "--driver", "ur", *table, "--start", "1", "--end", "3"])
        times["solve at 25 %"] = self.steps[-1][1]
        self.power_off()
        self.power_on("--start", "3")
        self.run("solve-100", [*UR3HANOI, solve, "--driver", "ur", *table, "--start", "3", "--end", "1"])
        times["solve at 100 %"] = self.steps[-1][1]
        self.power_off()
        return times


def inner(via: str, folder: Path) -> int:
    """The session itself (ROS 2: already inside the private network namespace)."""
    s = Session(via, folder)
    core = None
    try:
        if via == "ros":
            from tests.support.ros_support import free_port
            from ur3hanoi.interface.ros1.master import RosCore

            uri = f"http://127.0.0.1:{free_port()}"
            s.env["ROS_MASTER_URI"] = os.environ["ROS_MASTER_URI"] = uri
            os.environ.update(ROS_HOME=str(folder), ROS_IP="127.0.0.1")
            core = RosCore(uri)
            core.start()
        times = s.session()
    finally:
        s.power_off()
        if core is not None:
            core.stop()
    print(json.dumps(times))
    return 0


def rclpy_prefix() -> list[str]:
    """``env VAR=...`` of the Jazzy rclpy environment (built once in the user cache)."""
    from ur3hanoi.interface.ros2.rclpy_build import WHEELS, ensure_env
    from ur3hanoi.io.cache import cache_dir

    env = ensure_env(cache_dir(), WHEELS["jazzy"], sys.executable,
                     log=lambda m: print(f"# ros2-env: {m}", file=sys.stderr, flush=True))
    return ["env", *(f"{k}={v}" for k, v in env.variables("jazzy").items())]


def one(via: str, out: Path) -> dict[str, float]:
    folder = out / via
    folder.mkdir(parents=True, exist_ok=True)
    me = [sys.executable, str(Path(__file__).resolve()), "--inner", via, "--out", str(folder)]
    if via == "ros2":
        script = "ip link set lo up && ip link set lo multicast on && exec " + shlex.join([*rclpy_prefix(), *me])
        cmd = ["unshare", "-n", "bash", "-c", script]
    else:
        cmd = me
    proc = subprocess.run(cmd, cwd=REPO, capture_output=True, text=True, timeout=4 * STEP_TIMEOUT_S,
                          env=dict(os.environ, ROS_DOMAIN_ID="0"))
    if proc.returncode != 0:
        raise SystemExit(f"the {via} session failed:\n{proc.stdout[-3000:]}\n{proc.stderr[-3000:]}")
    times: dict[str, float] = json.loads(proc.stdout.strip().splitlines()[-1])
    return times


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", choices=("ros1", "ros2"))
    ap.add_argument("--out", type=Path, help="keep every step's output here (default: a temporary folder)")
    ap.add_argument("--inner", choices=("ros", "ros2"), help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.inner:
        return inner(args.inner, args.out)
    out = args.out or Path(tempfile.mkdtemp(prefix="ur3hanoi-first-session-"))
    print("first session on the official UR driver's stand-in, a student's station (towers moved 16-31 mm each, "
          "the row turned 4 deg); wall time per step [s]:")
    for label, via in (("ROS 1", "ros"), ("ROS 2", "ros2")):
        if args.only and args.only != ("ros1" if via == "ros" else "ros2"):
            continue
        times = one(via, out)
        poses = int(times.pop("poses"))
        total = sum(times.values())
        steps = ", ".join(f"{k} {v:.1f}" for k, v in times.items())
        print(f"- {label}: {steps}; {poses} poses taught; power-on to the first solved tower "
              f"{total - times['solve at 100 %']:.0f} s ({(total - times['solve at 100 %']) / 60:.1f} min), the whole "
              f"session {total:.0f} s")
    print(f"outputs: {out}")
    print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
