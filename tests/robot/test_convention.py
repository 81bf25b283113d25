"""ur3hanoi.robot.convention: the ROS 2 course bridge's joint convention, converted both ways, and tables that say which
convention they are in."""

from __future__ import annotations

import math

import numpy as np
import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from ur3hanoi import cli
from ur3hanoi.robot.convention import COURSE_OFFSET, from_controller, to_controller
from ur3hanoi.station.calibration import load_station
from ur3hanoi.tables.ik_table import generate_table


def test_the_bridge_offsets_joint_1_and_4() -> None:
    """The bridge sends destination[0] + pi/2 and destination[3] - pi/2 to the controller."""
    course = np.radians([30.0, -90.0, 90.0, 0.0, -90.0, 0.0])
    assert to_controller(course, "course") == pytest.approx(np.radians([120, -90, 90, -90, -90, 0]), abs=1e-15)
    assert from_controller(np.radians([120, -90, 90, -90, -90, 0]), "course") == pytest.approx(course, abs=1e-15)
    assert (math.pi / 2, 0.0, 0.0, -math.pi / 2, 0.0, 0.0) == COURSE_OFFSET
    with pytest.raises(ValueError, match="expected one of controller, course"):
        to_controller(course, "urdf")


@given(st.lists(st.floats(-6.0, 6.0), min_size=6, max_size=6), st.sampled_from(["controller", "course"]))
def test_round_trip_both_ways(q: list[float], convention: str) -> None:
    q_arr = np.array(q)
    assert np.abs(to_controller(from_controller(q_arr, convention), convention) - q_arr).max() < 1e-12
    assert np.abs(from_controller(to_controller(q_arr, convention), convention) - q_arr).max() < 1e-12


def test_course_table_is_converted_and_says_so(tmp_path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "lab2_data.yaml"
    assert cli.main(["tables", "ur3e_sim", "--key", "sim_pos", "-o", str(out), "--convention", "course"]) == 0
    text = out.read_text()
    line = next(x for x in text.splitlines() if "sim_pos generated from" in x)
    assert "UR3e" in line and "course bridge convention" in line
    q_written = np.array(yaml.safe_load(text)["sim_pos"])
    q_controller = generate_table(load_station("ur3e_sim")).q
    # The file holds 10 decimals (ur3hanoi.tables.ANGLE_DECIMALS): equal within that rounding.
    assert np.abs(to_controller(q_written, "course") - q_controller).max() < 1e-9
    assert np.abs(q_written - q_controller).max() == pytest.approx(math.pi / 2, abs=1e-9)
