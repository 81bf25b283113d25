"""Suction feedback profiles over a real roscore (marked ``ros``, real time): a lab program written on the real robot
(``AIN0 < 1.95 V`` after lifting means "block missing") solves on ``ros-station --suction-profile real`` and still
halts on a missing block; on the course simulator's levels (~1.9 V held) the same program halts falsely."""

from __future__ import annotations

import shlex
import sys
from pathlib import Path

import pytest

from tests.support import SUPPORT
from tests.support.ros_support import final_slots, free_port, requires_ros, ros_env, roscore, run, station, ur3hanoi_cmd
from ur3hanoi.station.suction_profile import LAB_SIM, REAL

pytestmark = [pytest.mark.ros, requires_ros]

THRESHOLD_V = 1.95  # a public student program's check, calibrated on a real station


def _program(tmp_path: Path, env: dict[str, str]) -> str:
    table = tmp_path / "lab2_data.yaml"
    assert run(ur3hanoi_cmd("tables", "lab_sim", "--key", "sim_pos", "-o", str(table)), env, 120).returncode == 0
    ros_env_cmd = shlex.join(ur3hanoi_cmd("ros-env", "--dir", str(tmp_path / "ros-env")))
    program = shlex.join([sys.executable, str(SUPPORT / "lab2_exec_starter.py"), "--simulator", "True", "--yaml",
                          str(table), "--ain0-below", str(THRESHOLD_V)])
    return f'eval "$({ros_env_cmd})" && exec {program}'


def test_real_robot_program_solves_on_the_real_profile(tmp_path: Path) -> None:
    env = ros_env(free_port(), tmp_path)
    script = _program(tmp_path, env)
    with roscore(env), station(env, tmp_path, "--suction-profile", "real") as st:
        assert "suction profile real" in st.log()  # the ready line names the profile
        result = run(["bash", "-c", script], env, 240.0, stdin="1\n3\n")
        assert result.returncode == 0, result.stdout + result.stderr
        report = st.stop()
    assert report["suction"]["profile"] == "real"
    assert report["suction"]["ain0_held"] == pytest.approx(REAL.ain0_held, abs=1e-12)
    assert final_slots(report) == {1: (3, 1), 2: (3, 2), 3: (3, 3)}
    assert report["final"]["at_home"] and not report["final"]["suction_on"]


@pytest.mark.parametrize(("profile", "removed"), [("real", "3"), ("lab_sim", None)])
def test_real_robot_program_halts_on_a_missing_block_or_on_simulator_levels(
        tmp_path: Path, profile: str, removed: str | None) -> None:
    """Real profile, top block removed: the first lift reads ~1.40 V and the program halts. lab_sim profile, every
    block there: a held block reads ~1.9 V < 1.95 V, so the same program halts on the first block it holds."""
    env = ros_env(free_port(), tmp_path)
    script = _program(tmp_path, env)
    extra = ["--remove-block", removed] if removed is not None else []
    with roscore(env), station(env, tmp_path, "--suction-profile", profile, *extra) as st:
        result = run(["bash", "-c", script], env, 120.0, stdin="1\n3\n")
        report = st.stop()
    out = result.stdout + result.stderr
    assert result.returncode == 1, out
    assert "Block not found at tower 1 height 3" in out
    ain0 = float(out.split("(AIN0 = ")[1].split(" V)")[0])
    level = REAL.ain0_free if profile == "real" else LAB_SIM.ain0_held
    assert abs(ain0 - level) < 0.1  # what the program read after lifting: the profile's level
    assert report["suction"]["profile"] == profile
    assert report["final"]["at_home"] and not report["final"]["suction_on"]
    grasps = [e for e in report["suction_events"] if e["kind"] == "grasp"]
    assert len(grasps) == (0 if removed is not None else 1)
