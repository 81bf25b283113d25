"""``ur3hanoi check-arm --driver ur`` against ``ros-station --driver ur`` over a real roscore (marked ``ros``, wall
clock; one station for the module): a cell that passes (a slider warning, the suction round trip with the cup free),
then every check shown failing: the program stopped (program and controller), a wrong suction pin, the other robot's
calibration, a home far from where the arm stands; and no driver at all."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support.ros_support import free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd
from tests.support.student_cell import write_student_station

pytestmark = [pytest.mark.ros, requires_ros]

PROGRAM = ("from ur3hanoi.interface.ros1.env import import_rospy; rospy = import_rospy(); "
           "import std_msgs.msg as m, sys, time; rospy.init_node('pendant', anonymous=True); "
           "p = rospy.Publisher('/ur3hanoi/program_running', m.Bool, queue_size=1, latch=True); "
           "time.sleep(0.5); p.publish(m.Bool(sys.argv[1] == 'run')); time.sleep(1.0)")


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[dict[str, str], Path, Any]]:
    folder = tmp_path_factory.mktemp("check_arm")
    write_student_station(folder / "student.yaml")
    env = ros_env(free_port(), folder)
    with roscore(env), station(env, folder, "--driver", "ur", "--calibration", str(folder / "student.yaml"),
                               "--speed-scaling", "0.5") as st:
        yield env, folder, st


def check(env: dict[str, str], calibration: Path | str, *args: str) -> tuple[int, dict[str, Any], str]:
    result = run(ur3hanoi_cmd("check-arm", "--via", "ros", "--driver", "ur", "--calibration", str(calibration),
                              "--json", *args), env, 60)
    report = json.loads(result.stdout)  # stdout is the JSON alone
    return result.returncode, {c["name"]: c for c in report["checks"]}, result.stderr


def variant(folder: Path, name: str, change: dict[str, Any]) -> Path:
    data = yaml.safe_load((folder / "student.yaml").read_text())
    for key, value in change.items():
        section, field = key.split(".")
        data.setdefault(section, {})[field] = value
    path = folder / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def test_a_ready_cell_passes_with_a_slider_warning_and_a_suction_round_trip(cell):
    env, folder, _ = cell
    code, checks, err = check(env, folder / "student.yaml", "--suction")
    assert code == 0, err
    assert {n: c["status"] for n, c in checks.items()} == {
        "driver": "ok", "program": "ok", "controller": "ok", "speed": "warn", "model": "ok", "home": "ok",
        "suction": "ok"}
    assert checks["speed"]["value"] == pytest.approx(0.5, abs=1e-6) and "above 25 %" in checks["speed"]["line"]
    assert 90.0 < checks["model"]["value"] < 160.0  # the CB3's 125 Hz
    assert checks["controller"]["value"] == "running"  # ros_control's list_controllers
    assert "DO0=1 DI0=0" in checks["suction"]["line"] and "DO0=0 DI0=0" in checks["suction"]["line"]
    assert len(err.strip().splitlines()) == 8 and err.strip().endswith("ready for the first move (read the warnings)")


def test_a_wrong_pin_the_other_robot_and_a_far_home_fail(cell):
    env, folder, _ = cell
    code, checks, _ = check(env, variant(folder, "pin", {"io.suction_output": 3}), "--suction")
    assert code == 2 and checks["suction"]["status"] == "fail"
    assert "DO3=1" in checks["suction"]["line"] and "stayed below" in checks["suction"]["line"]
    code, checks, _ = check(env, "ur3e_sim")
    assert code == 2 and checks["model"]["status"] == "fail"
    assert "a CB3 arm (UR3, 125 Hz), but ur3e_sim is for the UR3e" in checks["model"]["line"]
    code, checks, _ = check(env, variant(folder, "far", {"robot.home_deg": [80, -90, 90, -90, -90, 0]}))
    assert code == 2 and checks["home"]["status"] == "fail" and "from home at shoulder_pan_joint" in \
        checks["home"]["line"]
    assert checks["home"]["value"] == pytest.approx(0.698, abs=0.01)


def test_a_stopped_program_fails_program_and_controller(cell):
    env, folder, _ = cell
    stop = subprocess.run([sys.executable, "-c", PROGRAM, "stop"], env=env, timeout=30)
    try:
        assert stop.returncode == 0
        code, checks, err = check(env, folder / "student.yaml")
    finally:
        subprocess.run([sys.executable, "-c", PROGRAM, "run"], env=env, timeout=30)
    assert code == 2
    assert checks["program"]["status"] == "fail" and "External Control program is stopped" in checks["program"]["line"]
    assert checks["controller"]["status"] == "fail" and checks["controller"]["value"] == "stopped"
    assert "scaled_pos_joint_traj_controller is stopped (controller_manager)" in checks["controller"]["line"]
    assert "2 check(s) failed (program, controller)" in err


def test_no_driver_fails_the_first_check(tmp_path):
    env = ros_env(free_port(), tmp_path)
    with roscore(env):
        code, checks, _ = check(env, "lab_real", "--wait", "1")
    assert code == 2 and list(checks) == ["driver"] and checks["driver"]["status"] == "fail"


def test_on_the_course_topics_only_the_driver_and_home_are_told(tmp_path):
    env = ros_env(free_port(), tmp_path)
    with roscore(env), station(env, tmp_path, "--calibration", "lab_sim"):
        result = run(ur3hanoi_cmd("check-arm", "--via", "ros", "--calibration", "lab_sim"), env, 60)
        far = run(ur3hanoi_cmd("check-arm", "--via", "ros", "--calibration",
                               str(variant_of("lab_sim", tmp_path, {"robot.home_deg": [80, -90, 90, -90, -90, 0]}))),
                  env, 60)
    lines = result.stdout.strip().splitlines()
    assert result.returncode == 0, result.stdout + result.stderr
    assert lines[0].startswith("ok    driver     the course's driver publishes ur3/position")
    assert lines[1].startswith("ok    home       0.000 rad from home")
    assert [line.split()[0] for line in lines[2:7]] == ["skip"] * 5
    assert far.returncode == 2 and "fail  home       0.698 rad from home" in far.stdout


def variant_of(name: str, folder: Path, change: dict[str, Any]) -> Path:
    from ur3hanoi.io.resources import station_file

    (folder / "student.yaml").write_text(station_file(name).read_text())
    return variant(folder, f"{name}_changed", change)
