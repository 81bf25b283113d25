"""What the suction's feedback says about the vacuum: the sensor's no-vacuum level with the cup's output on, the
feedback as the messages quote it, the pins the hint names."""

from __future__ import annotations

import pytest

from ur3hanoi.interface.urdriver.facts import ANALOG_VOLTAGE, N_ANALOG, N_DIGITAL
from ur3hanoi.interface.urdriver.io import IoStates
from ur3hanoi.interface.urdriver.vacuum import feedback_text, no_vacuum, vacuum_hint
from ur3hanoi.station.suction_profile import LAB_SIM, REAL
from ur3hanoi.station.suction_wiring import SuctionWiring

UR3E = SuctionWiring(output=1, switch_input=0, sensor_input=0, generator=12)


def io(volts: float, on: tuple[int, ...] = (1, 12), held: bool = False) -> IoStates:
    return IoStates(tuple(i == 0 and held for i in range(N_DIGITAL)), tuple(i in on for i in range(N_DIGITAL)),
                    ((ANALOG_VOLTAGE, volts),) + ((ANALOG_VOLTAGE, 0.0),) * (N_ANALOG - 1),
                    ((ANALOG_VOLTAGE, 0.0),) * N_ANALOG)


@pytest.mark.parametrize(("profile", "volts", "expected"), [
    (LAB_SIM, 1.05, True), (LAB_SIM, 1.24, True), (LAB_SIM, 1.26, False), (LAB_SIM, 1.45, False),
    (REAL, 1.05, True), (REAL, 1.22, True), (REAL, 1.23, False), (REAL, 2.35, False),
])
def test_no_vacuum_is_the_sensor_nearer_its_off_level_than_its_free_level(profile, volts, expected):
    # the midpoints: lab_sim (1.05 + 1.45) / 2 = 1.25 V, real (1.05 + 1.40) / 2 = 1.225 V
    assert no_vacuum(io(volts), UR3E, profile) is expected


def test_with_the_cups_output_off_or_no_io_states_it_is_not_a_vacuum_fault():
    assert not no_vacuum(io(1.05, on=(12,)), UR3E, LAB_SIM)
    assert not no_vacuum(None, UR3E, LAB_SIM)


def test_the_feedback_quotes_the_calibrations_pins_and_with_outputs_the_suctions_outputs():
    assert feedback_text(io(1.0749), UR3E) == "DI0=0, AI0=1.07 V"
    assert feedback_text(io(2.1, on=(1,), held=True), UR3E, outputs=True) == "DI0=1, AI0=2.10 V, DO12=0, DO1=1"
    assert feedback_text(None, UR3E) == "no io_states"


def test_the_hint_names_the_generators_pin_or_that_the_calibration_names_none():
    assert "the vacuum generator's configurable output 4 (set_io pin 12) (io.vacuum_generator_output) on since " \
           "the start" in vacuum_hint(UR3E)
    none = vacuum_hint(SuctionWiring(output=0, switch_input=0, sensor_input=0))
    assert none.startswith(". The cup's digital output 0 (io.suction_output) is on but the vacuum sensor reads no "
                           "vacuum, and the calibration names no vacuum generator output")
    assert none.endswith("write that pin into io.vacuum_generator_output")
