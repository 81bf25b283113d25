"""``ros-solve --driver ur`` over a real roscore (marked ``ros``, real time): a solve through the UR driver's interface
served by ``ros-station --driver ur``, a halt, and a stand-in driver (Debian's actionlib) that rejects or aborts."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support import SUPPORT
from tests.support.ros_support import final_slots, free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd
from ur3hanoi.io.resources import station_file

pytestmark = [pytest.mark.ros, requires_ros]


def solve(env: dict[str, str], *args: str, timeout: float = 120.0) -> subprocess.CompletedProcess[str]:
    return run(ur3hanoi_cmd("ros-solve", "--driver", "ur", "--start", "1", "--end", "3", *args), env, timeout)


def test_a_solve_then_a_dropped_block_halt_through_the_ur_driver_interface(tmp_path):
    """One station for both: a 1-block solve from tower 1 to 3, then back, where the second grasp drops its block."""
    env = ros_env(free_port(), tmp_path)
    with roscore(env), station(env, tmp_path, "--driver", "ur", "--blocks", "1", "--drop-on-grasp", "2") as st:
        solved = solve(env, "--blocks", "1", "--json")
        mid = st.snapshot()
        halted = run(ur3hanoi_cmd("ros-solve", "--driver", "ur", "--start", "3", "--end", "1", "--blocks", "1"), env,
                     120.0)
        stop = [["/ur3hanoi/program_running", "Bool", {"data": False}]]  # the pendant's stop button
        assert run([sys.executable, str(SUPPORT / "ros_publisher.py"), json.dumps(stop)], env, 60.0).returncode == 0
        sent = st.snapshot()["goals"]["received"]
        refused = solve(env, "--blocks", "1")
        report = st.stop()
    assert refused.returncode == 2, refused.stdout + refused.stderr
    assert [line for line in refused.stderr.splitlines() if line.startswith("ur3hanoi: error")] == [
        "ur3hanoi: error: the robot program is not running (robot_program_running is false on "
        f"{env['ROS_MASTER_URI']}): the driver's trajectory controller refuses every goal until it runs; start the "
        "External Control program on the pendant"]
    assert solved.returncode == 0, solved.stdout + solved.stderr
    outcome = json.loads(solved.stdout.strip().splitlines()[-1])
    assert outcome["status"] == "solved" and outcome["moves"] == 1 and outcome["goals"] == 3
    # The path the client measured from every /joint_states it received (125 Hz; at most a few dropped under load).
    assert outcome["path_deviation_mm"] < 2.0 and outcome["joint_states_measured"] > 100 * outcome["executed_s"]
    assert final_slots(mid) == {1: (3, 1)} and mid["goals"]["succeeded"] == 3 and len(mid["io_calls"]) == 2
    assert halted.returncode == 3, halted.stdout + halted.stderr
    errors = [line for line in halted.stderr.splitlines() if line.startswith("ur3hanoi: error")]
    assert len(errors) == 1 and "green block 1 was dropped while carrying it from tower 3 to tower 1" in errors[0]
    assert len(report["halts"]) == 1 and report["halts"][0]["cycles"] >= 1 and report["goals"]["canceled"] == 1
    assert report["goals"]["received"] == sent and [e["running"] for e in report["program"]] == [False]  # refused
    assert report["final"]["at_home"] and not report["final"]["suction_on"]


def test_ctrl_c_mid_solve_leaves_every_output_off_and_the_station_reports_on_stdout(tmp_path):
    """A cell with a vacuum generator (pin 12, as ENME480's UR3e): the solve switches it on first; Ctrl-C at the
    start of move 2 stops the arm and switches every output off. The station runs without --report: its
    stdout is its JSON report alone, written when SIGTERM stops it."""
    env = ros_env(free_port(), tmp_path)
    cal = tmp_path / "generator.yaml"
    cal.write_text(station_file("lab_sim").read_text() + "io:\n  vacuum_generator_output: 12\n")
    with roscore(env), station(env, tmp_path, "--driver", "ur", "--blocks", "2", "--calibration", str(cal),
                               report=None) as st:
        proc = subprocess.Popen(ur3hanoi_cmd("ros-solve", "--driver", "ur", "--start", "1", "--end", "3", "--blocks",
                                             "2", "--calibration", str(cal)), env=env, text=True,
                                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                start_new_session=True)
        try:
            said = []
            assert proc.stdout is not None
            for line in proc.stdout:  # the solve's progress, until move 2 starts
                said.append(line)
                if line.startswith("move 2/3"):
                    proc.send_signal(signal.SIGINT)
                    break
            out, err = proc.communicate(timeout=30)
        finally:
            stop(proc)
        report = st.stop_json(signal.SIGTERM)
    assert proc.returncode == 130 and err.strip().splitlines()[-1] == "ur3hanoi ros-solve: interrupted", \
        "".join(said) + out + err
    assert said[1].startswith("vacuum generator on: configurable output 4 (set_io pin 12)"), said
    calls = [(c["pin"], c["state"]) for c in report["io_calls"]]
    assert calls[0] == (12, 1.0) and calls[-1] == (12, 0.0), calls
    assert report["final"]["digital_outputs_on"] == [] and not report["final"]["suction_on"]
    # Ctrl-C lands in the release of move 1 or the approach of move 2 (the line is printed between them): a goal
    # running then is canceled (the CPU-clock tests pin that case down); none is left running
    assert report["goals"]["canceled"] <= 1 and not report["final"]["goal_active"], (report["goals"], calls, err)


def fake_driver(env: dict[str, str], mode: str, log: Path) -> subprocess.Popen[str]:
    proc = subprocess.Popen([sys.executable, str(SUPPORT / "fake_ur_driver.py"), mode, str(log)], env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    assert proc.stdout is not None and proc.stdout.readline().strip() == "ready", proc.stderr.read() if proc.stderr \
        else ""
    return proc


def stop(proc: subprocess.Popen[str]) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()


@pytest.mark.parametrize(("mode", "line"), [
    ("abort", 'ended goal 1/3 (approach of move 1): aborted: PATH_TOLERANCE_VIOLATED (-4) "shoulder_pan_joint path '
              'error 0.250000"; suction off, the solve stops'),
    ("reject", "rejected goal 1/3 (approach of move 1): rejected: INVALID_JOINTS (-2) (no error string); suction off"),
])
def test_a_goal_the_driver_rejects_or_aborts_exit_2_with_its_code(tmp_path, mode, line):
    env = ros_env(free_port(), tmp_path)
    log = tmp_path / "fake.json"
    with roscore(env):
        proc = fake_driver(env, mode, log)
        try:
            result = solve(env, "--blocks", "1")
        finally:
            stop(proc)
    assert result.returncode == 2, result.stdout + result.stderr
    errors = [x for x in result.stderr.splitlines() if x.startswith("ur3hanoi: error")]
    assert len(errors) == 1 and line in errors[0]
    assert json.loads(log.read_text())["set_io"] == [[1, 0, 0.0]]  # suction off on the calibration's pin


def test_no_driver_exit_2_one_line(tmp_path):
    env = ros_env(free_port(), tmp_path)
    result = solve(env, "--blocks", "1", timeout=60.0)
    assert result.returncode == 2
    assert result.stderr.strip().splitlines()[-1].startswith(f"ur3hanoi: error: no ROS master answers at "
                                                             f"{env['ROS_MASTER_URI']}")
    with roscore(env):
        result = solve(env, "--blocks", "1", "--wait", "1", timeout=60.0)
    assert result.returncode == 2
    assert "is the UR driver (ur_robot_driver, or `ur3hanoi ros-station --driver ur`) running?" in \
        result.stderr.strip().splitlines()[-1]
