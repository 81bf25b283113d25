"""Jog steps by closed-form IK on the arm's branch: the suction point moves by exactly the step, the tool turns about
its own axis, and a step out of the workspace, below the table or across a singularity is refused with its reason."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.conftest import LAB_REAL
from ur3hanoi.robot.ik import branch_of
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, H_world_tcp
from ur3hanoi.teach.jog import JOG_ACCEL_RAD_S2, JOG_SPEED_RAD_S, MAX_STEP_JOINT_DEG, Jogger, move_time_s


@pytest.fixture(scope="module")
def base() -> Station:
    return load_station(LAB_REAL)


@pytest.fixture(scope="module")
def jog(base: Station) -> Jogger:
    return Jogger(base)


@pytest.fixture(scope="module")
def above(base: Station, jog: Jogger) -> np.ndarray:
    """Above tower 2 height 1, reached from home."""
    target = jog.go_above(np.array(base.q_home), base, 1, 0)
    assert target.q is not None
    return target.q


def test_go_above_reaches_the_base_pose_on_homes_branch(base: Station, jog: Jogger, above: np.ndarray) -> None:
    assert np.allclose(jog.H_world_tcp(above), H_world_tcp(base, 1, 0, ABOVE), atol=1e-9)
    assert branch_of(above) == branch_of(np.array(base.q_home))


@pytest.mark.parametrize("delta", [(1.0, 0.0, 0.0), (0.0, -5.0, 0.0), (0.0, 0.0, -20.0), (3.0, -4.0, 5.0)])
def test_a_step_moves_the_suction_point_by_exactly_the_step(jog: Jogger, above: np.ndarray,
                                                            delta: tuple[float, float, float]) -> None:
    step = jog.step(above, delta)
    assert step.q is not None and step.reason == ""
    before, after = jog.H_world_tcp(above), jog.H_world_tcp(step.q)
    assert np.allclose((after[:3, 3] - before[:3, 3]) * 1e3, delta, atol=1e-6)
    assert np.allclose(after[:3, :3], before[:3, :3], atol=1e-9)  # orientation kept
    assert np.allclose(step.p_world_m, after[:3, 3], atol=1e-12)


def test_a_turn_keeps_the_suction_point_and_turns_about_the_tool_axis(jog: Jogger, above: np.ndarray) -> None:
    step = jog.step(above, turn_deg=20.0)
    assert step.q is not None
    before, after = jog.H_world_tcp(above), jog.H_world_tcp(step.q)
    assert np.allclose(after[:3, 3], before[:3, 3], atol=1e-9)
    assert np.allclose(after[:3, 2], before[:3, 2], atol=1e-9)  # the suction axis stays
    angle = math.degrees(math.atan2(float(np.cross(before[:3, 0], after[:3, 0]) @ before[:3, 2]),
                                    float(before[:3, 0] @ after[:3, 0])))
    assert math.isclose(angle, 20.0, abs_tol=1e-6)


def test_steps_below_the_table_or_out_of_reach_are_refused(jog: Jogger, above: np.ndarray) -> None:
    low = jog.step(above, (0.0, 0.0, -200.0))
    assert low.refused and "below the table top" in low.reason and low.reason.startswith("step z -200 mm refused: ")
    far = jog.step(above, (1000.0, 0.0, 0.0))
    assert far.refused and "reachable workspace (no IK solution)" in far.reason


def test_a_step_across_a_singularity_is_refused(jog: Jogger) -> None:
    near_wrist_singularity = np.radians([120.0, -90.0, 90.0, -90.0, 0.5, 0.0])
    step = jog.step(near_wrist_singularity, (20.0, 0.0, 0.0))
    assert step.refused and "would jump across a singularity to another configuration" in step.reason
    assert f"more than {MAX_STEP_JOINT_DEG:g} deg" in step.reason


def test_a_step_takes_about_a_second_at_the_jog_caps(jog: Jogger, above: np.ndarray) -> None:
    step = jog.step(above, (20.0, 0.0, 0.0))
    assert step.q is not None
    t = move_time_s(above, step.q)
    d = float(np.max(np.abs(step.q - above)))
    assert 0.2 < t < 1.5 and t >= d / JOG_SPEED_RAD_S and t >= 2.0 * math.sqrt(d / JOG_ACCEL_RAD_S2) - 1e-9
