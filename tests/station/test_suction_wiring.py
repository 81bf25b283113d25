"""The calibration's optional io section: the suction's pins for the official UR drivers, defaulting to the
course's wiring on the calibration's arm, validated like every other field."""

from __future__ import annotations

import pytest
import yaml

from ur3hanoi.errors import CalibrationError
from ur3hanoi.io.resources import station_file
from ur3hanoi.station.calibration import load_station, parse_station, station_to_dict
from ur3hanoi.station.suction_wiring import SuctionWiring, output_name


def test_defaults_are_the_courses_wiring_per_arm():
    # UR3 (ECE 470): the course driver's set_digital_out(0, ...), no generator output; UR3e (ENME480): the bridge's
    # generator on pin 12 (configurable output 4) and the cup on digital output 1
    assert load_station("lab_sim").wiring == SuctionWiring(output=0, switch_input=0, sensor_input=0, generator=None)
    assert load_station("ur3e_sim").wiring == SuctionWiring(output=1, switch_input=0, sensor_input=0, generator=12)
    assert load_station("ur3e_sim").wiring.outputs == (12, 1)
    assert load_station("ur3e_sim").wiring.describe() == "suction on DO 1, vacuum generator on DO 12"
    assert load_station("lab_sim").wiring.describe() == "suction on DO 0"
    assert output_name(12) == "configurable output 4 (set_io pin 12)"
    assert output_name(1) == "digital output 1"
    assert output_name(17) == "tool output 1 (set_io pin 17)"


def calibration(tmp_path, io: str):
    path = tmp_path / "wired.yaml"
    path.write_text(station_file("lab_sim").read_text() + io)
    return path


def test_given_pins_are_read_and_written_back(tmp_path):
    st = load_station(calibration(tmp_path, "io:\n  suction_output: 16\n  vacuum_switch_input: 9\n"))
    assert st.wiring == SuctionWiring(output=16, switch_input=9, sensor_input=0)
    assert station_to_dict(st)["io"] == {"suction_output": 16, "vacuum_generator_output": None,
                                         "vacuum_switch_input": 9, "vacuum_sensor_input": 0}
    assert "io" not in station_to_dict(load_station("lab_sim"))  # the default is not written


def ur3e_calibration(tmp_path, io: str):
    path = tmp_path / "ur3e_cell.yaml"
    path.write_text(station_file("ur3e_sim").read_text() + io)
    return path


def test_the_generator_output_is_optional_null_or_a_pin(tmp_path):
    # a file written before the key existed: its arm's default (the ENME480 bridge's pin 12 on a UR3e)
    old = load_station(ur3e_calibration(tmp_path, "io:\n  suction_output: 1\n  vacuum_switch_input: 0\n"))
    assert old.wiring.generator == 12
    none = load_station(ur3e_calibration(tmp_path, "io:\n  vacuum_generator_output: null\n"))
    assert none.wiring == SuctionWiring(output=1, switch_input=0, sensor_input=0, generator=None)
    assert none.wiring.outputs == (1,)
    other = load_station(ur3e_calibration(tmp_path, "io:\n  vacuum_generator_output: 11\n"))
    assert other.wiring.generator == 11
    # written back, and read again to the same wiring
    text = yaml.safe_dump(station_to_dict(none), sort_keys=False)
    assert "vacuum_generator_output: null" in text
    assert parse_station(yaml.safe_load(text)).wiring == none.wiring


@pytest.mark.parametrize(("io", "message"), [
    ("io:\n  suction_output: 18\n", r"field 'io\.suction_output' = 18 is invalid: expected an integer in \[0, 17\]"),
    ("io:\n  vacuum_sensor_input: 2\n", r"'io\.vacuum_sensor_input' = 2 is invalid: expected an integer in \[0, 1\]"),
    ("io:\n  vacuum_switch_input: 1.5\n", r"'io\.vacuum_switch_input' = 1\.5 is invalid"),
    ("io:\n  suction_out: 1\n", r"field 'io\.suction_out' is unknown: did you mean 'io\.suction_output'\?"),
    ("io:\n  vacuum_generator_output: 18\n",
     r"^\S*wired\.yaml: field 'io\.vacuum_generator_output' = 18 is invalid: "
     r"expected an integer in \[0, 17\], or null$"),
    ("io:\n  vacuum_generator_output: 0\n",
     r"field 'io\.vacuum_generator_output' = 0 is invalid: expected an integer in \[0, 17\] other than "
     r"io\.suction_output \(0: the cup's own output\), or null"),
    ("io:\n  vacuum_generator: 12\n",
     r"field 'io\.vacuum_generator' is unknown: did you mean 'io\.vacuum_generator_output'\?"),
])
def test_bad_pins_are_one_clear_error(tmp_path, io, message):
    with pytest.raises(CalibrationError, match=message):
        load_station(calibration(tmp_path, io))
