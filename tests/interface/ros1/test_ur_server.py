"""``ros-station --driver ur`` over a real roscore (marked ``ros``, real time), used by clients written as others
write them: the UR driver's own integration test client (ported), a MoveIt-style client, a course-bridge-style
client, and ``set_io`` clients of both ``ur_msgs`` texts -- every one through Debian's actionlib and rospy."""

from __future__ import annotations

import json
import shlex
import sys
from collections.abc import Iterator

import pytest

from tests.support import SUPPORT
from tests.support.ros_support import Station, free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd

pytestmark = [pytest.mark.ros, requires_ros]


@pytest.fixture(scope="module")
def driver_station(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Station, dict[str, str]]]:
    tmp = tmp_path_factory.mktemp("ur_station")
    env = ros_env(free_port(), tmp)
    with roscore(env), station(env, tmp, "--driver", "ur") as st:
        yield st, env


def client(env: dict[str, str], kind: str) -> dict[str, object]:
    result = run([sys.executable, str(SUPPORT / "ur_driver_clients.py"), kind], env, 120.0)
    out = json.loads(result.stdout.strip().splitlines()[-1]) if result.stdout.strip() else {}
    assert result.returncode == 0, (kind, out, result.stderr[-2000:])
    return out


def test_set_io_serves_both_ur_msgs_texts(driver_station):
    out = client(driver_station[1], "set-io")
    assert out == {"ok": True, "noetic_1.4": True, "ur_msgs_1.3": True, "md5_any": True, "refused_pin_18": True}


def test_a_moveit_style_client(driver_station):
    out = client(driver_station[1], "moveit")
    assert out["code"] == 0 and out["final_error_rad"] < 0.01


def test_a_course_bridge_style_client_movej_per_waypoint(driver_station):
    out = client(driver_station[1], "bridge")
    assert out["codes"] == [0, 0, 0]


def test_the_ur_drivers_own_integration_test_client(driver_station):
    st, env = driver_station
    out = client(env, "integration")
    assert out["simple"] == [0, ""]
    assert out["illegal"] == [-1, "Trajectory message contains waypoints that are not strictly increasing in time."]
    assert out["scaled"] == [0, ""] and out["scaled_tight"] == [-5, ""]
    report = st.snapshot()
    goals = report["goals"]
    assert goals["rejected"] >= 1 and goals["aborted"] >= 1
    late = [g for g in report["goal_records"] if g.get("result") == "GOAL_TOLERANCE_VIOLATED (-5)"]
    assert late and late[-1]["lateness_s"] > 0.0
    assert report["driver"]["profile"] == "ros1_scaled" and report["control"]["rate_hz"] == 125.0


def test_a_stopped_program_preempts_the_goal_and_rejects_new_ones_without_a_text(driver_station):
    st, env = driver_station
    out = client(env, "program")
    assert out["ok"], out
    assert out["while_stopped"] == [5, -1, ""]  # REJECTED, INVALID_GOAL, no error string (goalCB)
    assert [e["running"] for e in st.snapshot()["program"]] == [False, True]


def test_urs_test_move_runs_unmodified_through_the_controller_manager_and_the_dashboard(driver_station, tmp_path):
    """UR's ``scripts/test_move`` (UniversalRobots/Universal_Robots_ROS_Driver @ 66510fd, byte for byte: git blob
    eeb41246967a4a388a48d65a96de8941ef24cb01) with its generated packages on PYTHONPATH, after a client that
    exercised the controller manager and the dashboard and left the scaled controller stopped: test_move lists,
    loads and switches it back (BEST_EFFORT), then sends its joint trajectory; "0" picks the scaled controller, "y"
    confirms the motion."""
    st, env = driver_station
    folder = tmp_path / "ros-env"
    ros_env_cmd = shlex.join(ur3hanoi_cmd("ros-env", "--dir", str(folder), "--driver", "ur"))
    assert run(["bash", "-c", ros_env_cmd], env, 120.0).returncode == 0
    env = {**env, "PYTHONPATH": f"{folder}:{env.get('PYTHONPATH', '')}"}
    out = client(env, "controllers")
    assert out["initial"]["scaled_pos_joint_traj_controller"] == "running", out
    assert out["initial"]["pos_joint_traj_controller"] == "stopped"
    assert [out["load_known"], out["load_again"], out["load_unknown"]] == [True, False, False]
    assert not out["start_running_strict"] and not out["two_on_the_joints"]
    assert out["program"] == [True, "Program running: true", True] and out["stop"] == [True, "Stopped"]
    assert out["after_stop"]["scaled_pos_joint_traj_controller"] == "stopped"
    assert out["after_stop"]["joint_state_controller"] == "running"  # a consistent controller
    assert not out["start_while_stopped"]  # the hardware interface refuses while the program is stopped
    assert out["play"] == [True, "Starting program"]
    assert out["after_play"]["scaled_pos_joint_traj_controller"] == "running"
    script = tmp_path / "test_move"
    script.write_bytes((SUPPORT / "upstream" / "ur_robot_driver_test_move.txt").read_bytes())
    program = shlex.join([sys.executable, str(script)])
    result = run(["bash", "-c", f'eval "$({ros_env_cmd})" && exec {program}'], env, 60.0, stdin="0\ny\n")
    assert result.returncode == 0, result.stdout[-2000:] + result.stderr[-2000:]
    assert "Trajectory execution finished in state 0" in result.stdout + result.stderr, result.stdout[-2000:]
    assert st.snapshot()["final"]["controllers"]["scaled_pos_joint_traj_controller"] == "running"
