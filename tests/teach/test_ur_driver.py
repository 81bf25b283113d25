"""``teach --driver ur`` over ROS 1 against ``ros-station --driver ur`` (a real roscore; marked ``ros``, wall clock;
one station for the module) on a station set up as a student would (tests/support/student_cell.py: every tower tens
of millimetres from lab_real's place, the row turned): a pose recorded by the non-interactive form with the program
stopped (recording needs no program), the jog keys refused with that reason, then a session through the
pseudo-terminal that jogs to the three contacts with teach's keys, holds a block with ``v`` on the first, and writes
the calibration and the table key (the ROS 2 driver: tests/teach/test_ur_driver_ros2.py)."""

from __future__ import annotations

import math
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pexpect
import pytest

from tests.support.ros_support import free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd
from tests.support.student_cell import ERRORS_MM, teach_session, write_student_station
from tests.support.teach_operator import JOG_RESOLUTION_MM, screen_text
from ur3hanoi.calibrate.taught import load_taught
from ur3hanoi.station.calibration import load_station

pytestmark = [pytest.mark.ros, requires_ros]

PROGRAM = ("from ur3hanoi.interface.ros1.env import import_rospy; rospy = import_rospy(); "
           "import std_msgs.msg as m, sys, time; rospy.init_node('pendant', anonymous=True); "
           "p = rospy.Publisher('/ur3hanoi/program_running', m.Bool, queue_size=1, latch=True); "
           "time.sleep(0.5); p.publish(m.Bool(sys.argv[1] == 'run')); time.sleep(1.0)")


def program(env: dict[str, str], running: bool) -> None:
    subprocess.run([sys.executable, "-c", PROGRAM, "run" if running else "stop"], env=env, timeout=30, check=True)


@pytest.fixture(scope="module")
def cell(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[dict[str, str], Path, Any]]:
    folder = tmp_path_factory.mktemp("teach_ur")
    write_student_station(folder / "student.yaml")
    env = ros_env(free_port(), folder)
    with roscore(env), station(env, folder, "--driver", "ur", "--calibration", str(folder / "student.yaml")) as st:
        yield env, folder, st


def spawn(env: dict[str, str], cwd: Path, *args: str, log: Path) -> Any:
    child = pexpect.spawn(sys.executable, ["-m", "ur3hanoi.cli", "teach", "--via", "ros", "--driver", "ur", "--base",
                                           "lab_real", *args], cwd=str(cwd), env=env, encoding="utf-8",
                          dimensions=(30, 150), timeout=60)
    child.logfile_read = log.open("a")
    return child


def test_recording_needs_no_program_and_jogging_is_refused_with_the_reason(cell):
    env, folder, _ = cell
    program(env, False)
    try:
        now = run(ur3hanoi_cmd("teach", "--via", "ros", "--driver", "ur", "--base", "lab_real", "-o",
                               str(folder / "now.yaml"), "--record-now", "1,3"), env, 60)
        assert now.returncode == 0, now.stdout + now.stderr
        assert "recorded tower 1 height 3: point 1 of" in now.stdout
        q = load_taught(folder / "now.yaml").points[0].q
        assert np.allclose(q, load_station("lab_real").q_home_array, atol=1e-3)  # the arm at home, by name
        child = spawn(env, folder, "-o", str(folder / "refused.yaml"), log=folder / "refused.txt")
        try:
            child.expect("the External Control program is stopped: record with freedrive")
            child.expect("next: tower 1 height 3")
            child.send("x")
            child.expect(r"jog refused: the External Control program is not running on the pendant[^\n]*"
                         r"recording needs no program")
            child.send("g")
            child.expect("jog refused: the External Control program is not running")
            child.sendintr()
            child.expect(pexpect.EOF)
        finally:
            child.close(force=True)
    finally:
        program(env, True)


def test_a_session_through_the_terminal_teaches_the_student_station(cell):
    env, folder, _ = cell
    raw = folder / "raw.txt"
    child = spawn(env, folder, "-o", "taught.yaml", "--table", "lab2_data.yaml", "--station-out", "station.yaml",
                  log=raw)
    try:
        seen = teach_session(child, load_station("lab_real"), load_station(folder / "student.yaml"), max_poses=3)
        child.expect(pexpect.EOF, timeout=120)
    finally:
        child.close(force=True)
    transcript = screen_text(raw.read_bytes().decode())
    assert child.exitstatus == 0, transcript
    assert seen["poses"] == [[1, 3], [2, 1], [3, 1]]
    assert seen["suction"][0].startswith("suction on: DO0=1 DI0=1") and "a block is held" in seen["suction"][0]
    assert seen["suction"][1].startswith("suction off: DO0=0 DI0=0")
    assert "wrote real_pos (3 towers x 3 heights x 2) to lab2_data.yaml" in transcript
    assert "not tracking" not in transcript  # actionlib's complaint about the previous jog goal stays off the screen
    assert "ur3hanoi ros-solve --driver ur --table lab2_data.yaml --key real_pos --calibration station.yaml" in \
        transcript
    fitted, hidden = load_station(folder / "station.yaml"), load_station(folder / "student.yaml")
    error_mm = np.linalg.norm(np.subtract(fitted.tower_origins, hidden.tower_origins), axis=1) * 1e3
    bound = [float(np.linalg.norm(e)) + math.sqrt(3) * JOG_RESOLUTION_MM / 2 + 0.2 for e in ERRORS_MM[:3]]
    assert np.all(error_mm <= bound), (error_mm, bound)
