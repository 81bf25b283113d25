"""The checks before the first move (ur3hanoi.interface.urdriver.check) on the CPU-clock loopback into a driver
station: each one passing and failing as the cell is (the model, measured on the wall clock, runs against the real
stand-ins: tests/cli/test_check_arm.py)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.interface.urdriver.test_cell import LoopbackCell
from tests.support.driver_helpers import station
from ur3hanoi.interface.urdriver.check import (
    HOME_FAR_RAD,
    check_controller,
    check_home,
    check_program,
    check_speed,
    check_suction,
)


@pytest.fixture()
def link() -> LoopbackCell:
    cell = LoopbackCell(station(calibration="lab_sim", speed_scaling=0.25))
    cell.connect()
    return cell


def test_a_ready_cell_passes(link: LoopbackCell) -> None:
    st = link.station.station
    program = check_program(link)
    assert (program.status, check_controller(link, program).status) == ("ok", "ok")
    speed = check_speed(link)
    assert speed.status == "ok" and speed.value == pytest.approx(0.25, abs=1e-9)
    assert check_home(link, st).status == "ok"
    suction = check_suction(link, st)
    assert suction.status == "ok", suction.line


def test_a_stopped_program_a_far_home_and_a_wrong_pin_fail(link: LoopbackCell) -> None:
    st = link.station.station
    link.station.on_program(False)
    link.wait(0.0)
    program = check_program(link)
    assert program.status == "fail" and check_controller(link, program).status == "fail"
    far = dataclasses.replace(st, q_home=tuple(np.asarray(st.q_home) + np.array([HOME_FAR_RAD + 0.1, 0, 0, 0, 0, 0])))
    home = check_home(link, far)
    assert home.status == "fail" and home.value == pytest.approx(HOME_FAR_RAD + 0.1, abs=1e-6)
    near = dataclasses.replace(st, q_home=tuple(np.asarray(st.q_home) + np.array([0.2, 0, 0, 0, 0, 0])))
    assert check_home(link, near).status == "warn"
    wrong = dataclasses.replace(st, wiring=dataclasses.replace(st.wiring, output=(st.wiring.output + 3) % 8))
    suction = check_suction(link, wrong)
    assert suction.status == "fail" and "the vacuum sensor stayed below" in suction.line
