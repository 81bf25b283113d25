"""The calibration's optional io section: the suction's pins for the official UR drivers, defaulting to the
course's wiring on the calibration's arm, validated like every other field."""

from __future__ import annotations

import pytest

from ur3hanoi.errors import CalibrationError
from ur3hanoi.io.resources import station_file
from ur3hanoi.station.calibration import load_station, station_to_dict
from ur3hanoi.station.suction_wiring import SuctionWiring


def test_defaults_are_the_courses_wiring_per_arm():
    assert load_station("lab_sim").wiring == SuctionWiring(output=0, switch_input=0, sensor_input=0)
    assert load_station("ur3e_sim").wiring == SuctionWiring(output=1, switch_input=0, sensor_input=0)


def calibration(tmp_path, io: str):
    path = tmp_path / "wired.yaml"
    path.write_text(station_file("lab_sim").read_text() + io)
    return path


def test_given_pins_are_read_and_written_back(tmp_path):
    st = load_station(calibration(tmp_path, "io:\n  suction_output: 16\n  vacuum_switch_input: 9\n"))
    assert st.wiring == SuctionWiring(output=16, switch_input=9, sensor_input=0)
    assert station_to_dict(st)["io"] == {"suction_output": 16, "vacuum_switch_input": 9, "vacuum_sensor_input": 0}
    assert "io" not in station_to_dict(load_station("lab_sim"))  # the default is not written


@pytest.mark.parametrize(("io", "message"), [
    ("io:\n  suction_output: 18\n", r"field 'io\.suction_output' = 18 is invalid: expected an integer in \[0, 17\]"),
    ("io:\n  vacuum_sensor_input: 2\n", r"'io\.vacuum_sensor_input' = 2 is invalid: expected an integer in \[0, 1\]"),
    ("io:\n  vacuum_switch_input: 1.5\n", r"'io\.vacuum_switch_input' = 1\.5 is invalid"),
    ("io:\n  suction_out: 1\n", r"field 'io\.suction_out' is unknown: did you mean 'io\.suction_output'\?"),
])
def test_bad_pins_are_one_clear_error(tmp_path, io, message):
    with pytest.raises(CalibrationError, match=message):
        load_station(calibration(tmp_path, io))
