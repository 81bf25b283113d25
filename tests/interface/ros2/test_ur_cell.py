"""``teach --driver ur`` and ``check-arm --driver ur`` on ROS 2 (ur3hanoi.interface.ros2.ur_cell, a real rclpy from
the ``ros2-env`` Jazzy environment) against ``ros2-station --driver ur``, inside a private network namespace, on a
station set up as a student would (tests/support/student_cell.py): the check, a pose recorded by the non-interactive
form (with the program stopped on the pendant: the check fails the program and the controller, recording works),
then a session through the pseudo-terminal that jogs to the three contacts by trajectory goals, holds a block
with ``v`` and writes the calibration and the table key; then the check on the other robot's calibration fails."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from tests.support.rclpy_support import build_env
from tests.support.ros2_support import NETNS_PROBLEM, REPO, in_netns
from tests.support.student_cell import write_student_station
from ur3hanoi.calibrate.taught import load_taught
from ur3hanoi.station.calibration import load_station

pytestmark = [pytest.mark.rclpy, pytest.mark.skipif(NETNS_PROBLEM is not None, reason=NETNS_PROBLEM or "")]


def test_check_record_and_a_terminal_session_on_the_ros2_driver(tmp_path: Path) -> None:
    env = build_env("jazzy")
    write_student_station(tmp_path / "student.yaml")
    pre = env.station_prefix()
    # 125 Hz, the UR3's rate (lab_real is a UR3): station and clients all run Python on a shared machine here.
    station = (f"{pre} $UR3HANOI ros2-station --driver ur --calibration {tmp_path}/student.yaml --rate 125 "
               f"--report {tmp_path}/report.json")
    check = f"{pre} $UR3HANOI check-arm --via ros2 --driver ur --json --suction"
    script = "\n".join([
        f"{station} > {tmp_path}/st.out 2> {tmp_path}/st.err &", "ST=$!", f"wait_ready {tmp_path}/st.err || exit 90",
        f"{check} --calibration {tmp_path}/student.yaml > {tmp_path}/check.json 2> {tmp_path}/check.err; "
        f"echo $? > {tmp_path}/check.code",
        f"{pre} {sys.executable} -m tests.support.pendant stop > {tmp_path}/stop.out 2>&1 || exit 91",
        f"{check} --calibration {tmp_path}/student.yaml > {tmp_path}/stopped.json 2> /dev/null; "
        f"echo $? > {tmp_path}/stopped.code",
        f"{pre} $UR3HANOI teach --via ros2 --driver ur --base lab_real -o {tmp_path}/now.yaml --record-now 1,3 "
        f"> {tmp_path}/now.out 2>&1; echo $? > {tmp_path}/now.code",
        f"{pre} {sys.executable} -m tests.support.pendant play > {tmp_path}/play.out 2>&1 || exit 92",
        f"{pre} {sys.executable} -m tests.support.student_cell {tmp_path} 3 --via ros2 --driver ur "
        f"> {tmp_path}/session.json 2> {tmp_path}/session.err",
        f"{check} --calibration ur3e_sim > {tmp_path}/other.json 2> /dev/null; echo $? > {tmp_path}/other.code",
        "kill -INT $ST; wait $ST; echo \"station exit $?\" >&2"]) + "\n"
    result = in_netns(script, 420.0, REPO)
    assert result.returncode == 0 and "station exit 0" in result.stderr, result.stderr
    checks = {c["name"]: c for c in json.loads((tmp_path / "check.json").read_text())["checks"]}
    assert int((tmp_path / "check.code").read_text()) == 0, (tmp_path / "check.err").read_text()
    assert checks["speed"]["status"] == "warn" and checks["speed"]["value"] == pytest.approx(1.0, abs=1e-6)
    assert checks["model"]["status"] == "ok" and checks["home"]["status"] == "ok"
    assert checks["program"]["status"] == "ok" and checks["controller"]["value"] == "active"
    # The program stopped on the pendant (the dashboard's stop): the program and the controller fail; recording works.
    stopped = {c["name"]: c for c in json.loads((tmp_path / "stopped.json").read_text())["checks"]}
    assert int((tmp_path / "stopped.code").read_text()) == 2
    assert stopped["program"]["status"] == "fail" and stopped["controller"]["status"] == "fail"
    assert "scaled_joint_trajectory_controller is inactive (controller_manager)" in stopped["controller"]["line"]
    assert checks["suction"]["status"] == "ok", checks["suction"]
    assert int((tmp_path / "now.code").read_text()) == 0, (tmp_path / "now.out").read_text()
    assert np.allclose(load_taught(tmp_path / "now.yaml").points[0].q, load_station("lab_real").q_home_array,
                       atol=1e-3)
    seen = json.loads((tmp_path / "session.json").read_text())
    transcript = (tmp_path / "transcript.txt").read_text()
    assert seen["exit"] == 0 and seen["poses"] == [[1, 3], [2, 1], [3, 1]], transcript
    assert "a block is held" in seen["suction"][0] and seen["suction"][1].startswith("suction off")
    assert "ur3hanoi ros2-solve --driver ur --table" in transcript
    fitted, hidden = load_station(tmp_path / "station.yaml"), load_station(tmp_path / "student.yaml")
    error_mm = np.linalg.norm(np.subtract(fitted.tower_origins, hidden.tower_origins), axis=1) * 1e3
    assert np.all(error_mm < 2.0), error_mm
    other = {c["name"]: c for c in json.loads((tmp_path / "other.json").read_text())["checks"]}
    assert int((tmp_path / "other.code").read_text()) == 2 and other["model"]["status"] == "fail"
