"""``ros2-solve --driver ur`` (ur3hanoi.interface.ros2.ur_client) with a real rclpy (the ``ros2-env`` environments),
inside a private network namespace:

- Jazzy, against ``ros2-station --driver ur``: one block solved, then a solve stopped by SIGTERM in its first goal
  (every output off, the vacuum generator's too; the station's stdout its JSON report alone); a block dropped during
  the carry halts the solve (exit 3, suction off, the arm home), the cancel recorded with its latency;
- Kilted, against an rclpy action server standing in for the driver (tests/support/ur_driver_standin.py): no driver
  within the wait, a goal rejected at send_goal, a goal aborted with PATH_TOLERANCE_VIOLATED: one line each, exit 2,
  the suction off.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from tests.support import SUPPORT
from tests.support.rclpy_support import build_env
from tests.support.ros2_support import NETNS_PROBLEM, REPO, in_netns
from ur3hanoi.interface.ros2.ur_driver import names_for
from ur3hanoi.station.calibration import load_station

pytestmark = [pytest.mark.rclpy, pytest.mark.skipif(NETNS_PROBLEM is not None, reason=NETNS_PROBLEM or "")]

SOLVE = "$UR3HANOI ros2-solve --driver ur --start 1 --end 3 --blocks 1"


def _with_station(station: str, solve: str, tmp: Path, name: str, then: tuple[str, ...] = (),
                  sig: str = "INT") -> list[str]:
    """Lines: start ``station`` in the background, wait for its ready line, run ``solve`` (its exit code into
    ``<name>.code``), then the lines ``then``, stop the station with SIG."""
    return [f"{station} > {tmp}/{name}.st.out 2> {tmp}/{name}.st.err &", "ST=$!",
            f"wait_ready {tmp}/{name}.st.err || exit 90",
            f"{solve} > {tmp}/{name}.out 2> {tmp}/{name}.err; echo $? > {tmp}/{name}.code", *then,
            f"kill -{sig} $ST; wait $ST; echo \"station exit $?\" >&2"]


def _terminated(solve: str, tmp: Path, name: str) -> tuple[str, ...]:
    """Lines: run ``solve`` in the background, SIGTERM it once it has said ``move 1/1`` (its first goal sent)."""
    return (f"{solve} > {tmp}/{name}.out 2> {tmp}/{name}.err & SV=$!",
            f"for _ in $(seq 1 600); do grep -qs '^move 1/1' {tmp}/{name}.out && break; sleep 0.05; done",
            f"kill -TERM $SV; wait $SV; echo $? > {tmp}/{name}.code")


def _read(tmp: Path, name: str) -> tuple[int, str, str]:
    return int((tmp / f"{name}.code").read_text()), (tmp / f"{name}.out").read_text(), (tmp / f"{name}.err").read_text()


def test_solves_one_block_and_halts_on_a_dropped_block(tmp_path: Path) -> None:
    env = build_env("jazzy")
    # 125 Hz (the UR3's rate): station and client both run Python here; the UR3e's 500 Hz is tested with the driver's
    # own clients (test_ur_station.py) and measured in bench/bench_driver.py.
    station = f"{env.station_prefix()} $UR3HANOI ros2-station --driver ur --blocks 1 --rate 125"
    solve = f"{env.station_prefix()} {SOLVE}"
    # The first station without --report: its stdout is its JSON report alone, written when SIGTERM stops it. After
    # the solve, a second one (back to tower 1) is stopped by SIGTERM during its first goal.
    back = f"{env.station_prefix()} $UR3HANOI ros2-solve --driver ur --start 3 --end 1 --blocks 1"
    script = "\n".join([*_with_station(station, f"{solve} --json", tmp_path, "ok",
                                       _terminated(back, tmp_path, "term"), sig="TERM"),
                        *_with_station(f"{station} --drop-on-grasp 1 --report {tmp_path}/halt.json", solve, tmp_path,
                                       "halt")]) + "\n"
    result = in_netns(script, 240.0, REPO)
    assert result.returncode == 0 and result.stderr.count("station exit 0") == 2, result.stderr
    code, out, err = _read(tmp_path, "ok")
    assert code == 0, err
    outcome = json.loads(out.strip().splitlines()[-1])
    assert outcome["status"] == "solved" and outcome["ros_distro"] == "jazzy"
    assert outcome["path_deviation_mm"] < 2.0 and outcome["joint_states_measured"] > 100 * outcome["executed_s"]
    ok = json.loads((tmp_path / "ok.st.out").read_text())  # the whole of the station's stdout
    assert [(b["block"], b["tower"], b["height"]) for b in ok["final"]["blocks"]] == [(1, 3, 1)]
    assert ok["goals"]["aborted"] == 0 and ok["goals"]["rejected"] == 0 and ok["goals"]["succeeded"] >= 3
    # ur3e_sim is wired as ENME480's cells: the vacuum generator on pin 12, switched on first and off last by each
    # solve, also by the one SIGTERM stopped during its first goal (canceled, the arm stopped where it was)
    code, out, err = _read(tmp_path, "term")
    assert code == 143 and err.strip().splitlines()[-1] == "ur3hanoi ros2-solve: terminated (SIGTERM)", out + err
    calls = [(c["pin"], c["state"]) for c in ok["io_calls"]]
    assert calls[0] == (12, 1.0) and calls[-1] == (12, 0.0) and calls.count((12, 1.0)) == 2, calls
    assert ok["final"]["digital_outputs_on"] == [] and not ok["final"]["suction_on"]
    assert ok["goals"]["canceled"] == 1 and not ok["final"]["goal_active"]

    code, _, err = _read(tmp_path, "halt")
    lines = [x for x in err.splitlines() if x.startswith("ur3hanoi: error:")]
    assert code == 3 and len(lines) == 1, err
    halt = json.loads((tmp_path / "halt.json").read_text())
    assert halt["final"]["at_home"] and not halt["final"]["suction_on"]
    assert halt["goals"]["canceled"] == 1
    (h,) = halt["halts"]  # its latency (cycles from the feedback's loss to the cancel) is bench_driver.py's figure
    assert isinstance(h["cycles"], int) and h["cycles"] >= 0, h


def test_no_driver_rejected_and_aborted_goals_end_with_one_line(tmp_path: Path) -> None:
    env = build_env("kilted")
    home = json.dumps([float(x) for x in load_station("ur3e_sim").q_home])
    action = names_for("kilted").follow_joint_trajectory
    solve = f"{env.station_prefix()} {SOLVE} --ros-distro kilted"
    lines = [f"{solve} --wait 1 > {tmp_path}/none.out 2> {tmp_path}/none.err; echo $? > {tmp_path}/none.code"]
    for mode in ("reject", "abort"):
        standin = env.peer_command(str(SUPPORT / "ur_driver_standin.py"), mode, home, action)
        lines += _with_station(standin, solve, tmp_path, mode)
    result = in_netns("\n".join(lines) + "\n", 180.0, REPO)
    assert result.returncode == 0, result.stderr

    code, _, err = _read(tmp_path, "none")
    assert code == 2 and err.count("\n") == 1 and err.startswith("ur3hanoi: error: no UR driver on ROS_DOMAIN_ID 0")
    assert "/joint_states" in err and action in err

    for mode, expected in (("reject", "rejected"), ("abort", 'aborted: PATH_TOLERANCE_VIOLATED (-4) "Aborted due to '
                                                             'path tolerance violation"')):
        code, _, err = _read(tmp_path, mode)
        errors = [x for x in err.splitlines() if x.startswith("ur3hanoi: error:")]
        assert code == 2 and len(errors) == 1 and expected in errors[0], err
        standin = json.loads((tmp_path / f"{mode}.st.out").read_text().strip().splitlines()[-1])
        assert standin["goals"] == 1
        # ur3e_sim's wiring: the generator (pin 12) on first; at the end the cup off, then the generator
        assert standin["io_calls"] == [[1, 12, 1.0], [1, 1, 0.0], [1, 12, 0.0]], standin["io_calls"]


def test_a_stopped_program_refuses_the_solve_and_a_stop_mid_solve_ends_it_exit_3(tmp_path: Path) -> None:
    """The stand-in driver (Jazzy) with the External Control program stopped from the start, then stopping during the
    first goal: the client reads the latched robot_program_running over DDS."""
    env = build_env("jazzy")
    home = json.dumps([float(x) for x in load_station("ur3e_sim").q_home])
    action = names_for("jazzy").follow_joint_trajectory
    solve = f"{env.station_prefix()} {SOLVE}"
    lines: list[str] = []
    for mode in ("stopped", "stop-mid"):
        lines += _with_station(env.peer_command(str(SUPPORT / "ur_driver_standin.py"), mode, home, action), solve,
                               tmp_path, mode)
    result = in_netns("\n".join(lines) + "\n", 120.0, REPO)
    assert result.returncode == 0, result.stderr
    code, _, err = _read(tmp_path, "stopped")
    errors = [x for x in err.splitlines() if x.startswith("ur3hanoi: error:")]
    assert code == 2 and errors == ["ur3hanoi: error: the robot program is not running (robot_program_running is "
                                    "false on ROS_DOMAIN_ID 0 (loopback, jazzy)): the driver's trajectory controller "
                                    "refuses every goal until it runs; start the External Control program on the "
                                    "pendant"], err
    standin = json.loads((tmp_path / "stopped.st.out").read_text().strip().splitlines()[-1])
    assert standin["goals"] == 0  # refused before any goal
    code, _, err = _read(tmp_path, "stop-mid")
    errors = [x for x in err.splitlines() if x.startswith("ur3hanoi: error:")]
    assert code == 3 and len(errors) == 1, err
    assert errors[0].startswith("ur3hanoi: error: the External Control program stopped on the robot during goal 1/3")
    assert 'INVALID_GOAL (-1) "Current goal cancelled during deactivate transition."' in errors[0]
    assert "the arm stopped where it was, suction off" in errors[0]
    standin = json.loads((tmp_path / "stop-mid.st.out").read_text().strip().splitlines()[-1])
    # suction off at the end: the cup's output, then the vacuum generator's (ur3e_sim: pin 12)
    assert standin["goals"] == 1 and standin["io_calls"][-2:] == [[1, 1, 0.0], [1, 12, 0.0]], standin["io_calls"]


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
