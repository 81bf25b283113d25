"""The simulated UR robot under a streaming controller: exact within its limits, limited and scaled beyond them,
held by an obstacle."""

from __future__ import annotations

import numpy as np
import pytest

from ur3hanoi.errors import SimulationError
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.servo_world import ServoWorld
from ur3hanoi.station.calibration import load_station

DT = 0.008


@pytest.fixture(scope="module")
def station():
    return load_station("lab_sim")


def world(station, slider: float = 1.0) -> ServoWorld:
    return ServoWorld(station, 0, 3, config=SimConfig(period_s=DT), slider=slider)


def ramp(q0: np.ndarray, speed: np.ndarray, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """From rest towards constant ``speed`` [rad/s] in 0.5 s (velocity a smoothstep): the state at time ``t``."""
    T = 0.5
    if t < T:
        u = t / T
        return (q0 + speed * T * (u ** 3 - u ** 4 / 2), speed * (3 * u ** 2 - 2 * u ** 3),
                speed * (6 * u - 6 * u ** 2) / T)
    return q0 + speed * (T / 2 + t - T), speed.copy(), np.zeros_like(speed)


def drive(w: ServoWorld, q0: np.ndarray, speed: np.ndarray, cycles: int) -> list[float]:
    """Step the robot along the ramp in scaled time, as the scaled controller does; the speed scalings."""
    tau, out = 0.0, []
    for _ in range(cycles):
        s = w.speed_scaling
        tau += DT * s
        q, qd, qdd = ramp(q0, speed, tau)
        w.step(q, qd * s, qdd * s * s)
        out.append(w.speed_scaling)
    return out


def test_a_target_within_the_limits_is_followed_exactly(station):
    w = world(station)
    q0 = w.q
    speed = np.array([1.0, 0.5, -0.5, 1.0, 1.0, 1.0])
    assert set(drive(w, q0, speed, 150)) == {1.0} and not w.limited
    np.testing.assert_allclose(w.ref_q, ramp(q0, speed, 150 * DT)[0], atol=1e-12)
    assert np.max(np.abs(w.q - w.ref_q)) < 0.02  # the servo's own lag


def test_a_target_beyond_the_speed_limit_is_limited_and_the_robot_scales_itself_down(station):
    w = world(station)
    q0 = w.q
    speed = np.array([2 * np.pi, 0, 0, 0, 0, 0])  # twice the base's 180 deg/s
    scalings = drive(w, q0, speed, 200)
    peak = float(np.max(np.abs(w.qd)))
    assert scalings[-1] == pytest.approx(0.5, abs=0.02)
    assert peak <= np.pi * 1.05


def test_the_slider_is_reported(station):
    assert world(station, 0.25).speed_scaling == 0.25
    with pytest.raises(SimulationError, match=r"speed slider 0\.0 is invalid"):
        world(station, 0.0)


def test_a_held_arm_stays_while_its_target_moves_and_moves_again_when_released(station):
    w = world(station)
    q0 = w.q
    w.hold_arm(0.4)
    speed = np.array([0.5, 0, 0, 0, 0, 0])
    drive(w, q0, speed, 49)
    assert w.held and abs(w.q[0] - q0[0]) < 2e-3 and w.ref_q[0] - q0[0] > 0.05
    tau = 49 * DT
    for _ in range(100):
        tau += DT
        w.step(*ramp(q0, speed, tau))
    assert not w.held and abs(w.q[0] - w.ref_q[0]) < 0.02
