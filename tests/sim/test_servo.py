"""ur3hanoi.sim.servo: the one servo law, its command line per physics step, and what its acceleration feed-forward
buys the movej world."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from ur3hanoi.errors import SimulationError
from ur3hanoi.sim import MoveJWorld, SimConfig, build_task_scene
from ur3hanoi.sim.servo import JointServo
from ur3hanoi.station.calibration import Station
from ur3hanoi.tables.ik_table import generate_table


def test_each_physics_step_holds_its_mean_point_on_the_cycles_line(lab_sim: Station) -> None:
    scene = build_task_scene(lab_sim, 0, 1)
    servo = JointServo(scene, 0.008, accel_feedforward=False)
    assert servo.n_steps == 4
    c0 = lab_sim.q_home_array
    c1 = c0 + np.linspace(0.01, 0.06, 6)
    servo.reset(c0)
    seen = []
    servo.cycle(c1, after_first_step=lambda: seen.append(scene.data.ctrl[servo.act_ids].copy()))
    # Step j of 4 holds the command at (j + 1/2) / 4 of the way: the first 1/8, the last 7/8.
    np.testing.assert_allclose(seen[0], c0 + 0.125 * (c1 - c0), rtol=0, atol=1e-15)
    np.testing.assert_allclose(scene.data.ctrl[servo.act_ids], c0 + 0.875 * (c1 - c0), rtol=0, atol=1e-15)
    servo.hold(c1)
    np.testing.assert_array_equal(scene.data.ctrl[servo.act_ids], c1)


def test_the_acceleration_feed_forward_is_the_inertia_times_the_cycles_mean_acceleration(lab_sim: Station) -> None:
    scene = build_task_scene(lab_sim, 0, 1)
    servo = JointServo(scene, 0.008)
    q = lab_sim.q_home_array
    servo.reset(q)  # at rest: the last reference acceleration is zero
    acc = np.array([1.0, -2.0, 3.0, 0.5, -0.5, 4.0])
    d, m = scene.data, scene.model
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    arm = scene.arm_dadr
    expected = q + M[np.ix_(arm, arm)] @ (0.5 * acc) / servo.kp
    servo.cycle(q, acc)
    # The inertia is the one at the pose the cycle started from; the arm barely moved in 8 ms.
    np.testing.assert_allclose(scene.data.ctrl[servo.act_ids], expected, rtol=0, atol=1e-12)


def test_the_period_must_be_a_multiple_of_the_physics_step(lab_sim: Station) -> None:
    scene = build_task_scene(lab_sim, 0, 1)
    with pytest.raises(SimulationError, match=r"control period 0\.003 s is invalid: expected a multiple"):
        JointServo(scene, 0.003)


def _worst_arrival_error(world: MoveJWorld, poses: list[np.ndarray]) -> float:
    """Largest joint distance [rad] from the destination when each movej's reference comes to rest."""
    worst = 0.0
    for q in poses:
        world.begin(q, 4.0, 4.0, False)
        while world.moving:
            world.step()
        worst = max(worst, world.error_to_target())
        for _ in range(10):  # rest 80 ms, like a lab program waiting for the arm
            world.step()
    return worst


def test_the_movej_world_arrives_closer_with_the_acceleration_feed_forward(lab_sim: Station) -> None:
    """The stations adopted solve's law: on the lab's full-speed moves (v = a = 4) through every table pose, the
    acceleration feed-forward brings the arm to its destination's 0.5 mrad (the lab's wait) as the profile ends
    (measured: 0.10 mrad off at worst, 0.31 mrad with velocity feed-forward alone)."""
    Q = generate_table(lab_sim).q
    poses = [Q[t, h, k] for t in range(3) for h in range(3) for k in (1, 0, 1)]
    with_ff = _worst_arrival_error(MoveJWorld(lab_sim, 0, 3), poses)
    without = _worst_arrival_error(MoveJWorld(lab_sim, 0, 3, config=SimConfig(accel_feedforward=False)), poses)
    assert with_ff < 0.5 * without
    assert with_ff < 0.0002  # [rad]
