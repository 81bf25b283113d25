"""teach's driver on the official UR driver (ur3hanoi.interface.urdriver.cell) on the CPU-clock loopback into a
driver station (no middleware): the joint history, jog goals at teach's caps that arrive, refused while the program
is stopped, and the suction switched and read back from io_states (the generator first where one is named)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tests.support.driver_helpers import station
from ur3hanoi.errors import DriverError
from ur3hanoi.interface.urdriver.cell import (
    HISTORY_S,
    DriverArm,
    JointHistory,
    jog_speed_fraction,
    suction_outputs,
    switch_suction,
)
from ur3hanoi.interface.urdriver.facts import ROS1
from ur3hanoi.interface.urdriver.loopback import LoopbackTransport
from ur3hanoi.station.calibration import load_station


class LoopbackCell(LoopbackTransport):
    """The loopback with what a binding's cell link adds (the program state comes from the station's output)."""

    def __init__(self, *args, **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.history = self.record = JointHistory()
        self.action = ROS1.follow_joint_trajectory

    def program_running(self) -> bool | None:
        return self.latest().program_running

    def controller_state(self) -> str | None:
        return None

    def simulated(self) -> bool:
        return True


def test_the_history_keeps_the_last_seconds_and_counts_every_state() -> None:
    h = JointHistory()
    import time

    now = time.monotonic()
    for k in range(400):  # 4 s at 100 Hz, the last one now
        h.add(now - 4.0 + 0.01 * (k + 1), np.full(6, float(k)))
    assert h.count == 400
    kept = h.window(10.0)
    assert len(kept) == pytest.approx(HISTORY_S / 0.01, abs=2) and kept[-1][1][0] == 399.0
    assert len(h.window(0.5)) == pytest.approx(50, abs=2)


def test_the_jog_speed_keeps_every_joint_within_teach_s_caps() -> None:
    lab = load_station("lab_real")
    f = jog_speed_fraction(lab, 0.35, 0.7)
    assert f * max(lab.limits.v_max) <= 0.35 + 1e-12 and f * max(lab.limits.a_max) <= 0.7 + 1e-12
    assert f == pytest.approx(min(0.35 / max(lab.limits.v_max), 0.7 / max(lab.limits.a_max)), rel=1e-12)


def test_a_jog_goal_arrives_and_a_stopped_program_refuses_the_next() -> None:
    st = station(calibration="lab_sim")
    link = LoopbackCell(st)
    link.connect()
    arm = DriverArm(link, st.station)
    q0 = st.station.q_home_array
    target = q0 + np.radians([3.0, -2.0, 2.0, 0.0, 1.0, 0.0])
    arm.send(target, 0.35, 0.7)
    for _ in range(2000):
        if not arm.goal_running():
            break
        link.wait(0.0)
    assert arm.goal_problem() == ""
    assert np.max(np.abs(link.latest().q - target)) < 2e-4
    st.on_program(False)
    link.wait(0.0)
    assert arm.program_running() is False
    assert arm.jog_problem().startswith("jog refused: the External Control program is not running")
    with pytest.raises(DriverError, match="External Control program is not running"):
        arm.send(q0, 0.35, 0.7)


def test_the_suction_is_switched_and_read_back_generator_first() -> None:
    st = station(calibration="lab_sim")
    link = LoopbackCell(st)
    link.connect()
    arm = DriverArm(link, st.station)
    said = arm.suction(True)
    assert said.startswith(f"suction on: DO{st.station.wiring.output}=1") and "no block held" in said
    assert arm.suction(False).startswith(f"suction off: DO{st.station.wiring.output}=0")
    wired = dataclasses.replace(st.station, wiring=dataclasses.replace(st.station.wiring, output=5))
    wired = dataclasses.replace(wired, wiring=dataclasses.replace(wired.wiring, generator=12))
    assert suction_outputs(wired) == (12, 5)
    switch_suction(link, wired, True)
    assert all(link.latest().io.digital_out[p] for p in suction_outputs(wired))
    with pytest.raises(DriverError, match="success = false"):
        switch_suction(link, dataclasses.replace(wired, wiring=dataclasses.replace(wired.wiring, output=18)), True)
