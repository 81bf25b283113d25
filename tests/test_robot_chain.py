"""NumPy FK of the URDF chain (:mod:`ur3hanoi.robot_chain`) against Pinocchio's FK, the reference model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot import JOINT_NAMES, ToolOffset, Ur3Model, urdf_text
from ur3hanoi.robot_chain import axis_rotation, parse_chain, rigid_inverse, rpy_matrix
from ur3hanoi.robot_registry import UR3, UR3E

TOOLS = (
    ToolOffset("ee_link", (0.059, 0.0535, 0.0), (0.0, math.pi / 2, 0.0)),  # the lab's suction cup
    ToolOffset("tool0", (0.01, -0.02, 0.13), (0.3, -0.2, 1.1)),
)
FRAMES = ("base", "base_link", "tool0", "ee_link", "tcp")


@pytest.mark.parametrize("robot", [UR3, UR3E], ids=lambda r: r.name)
@pytest.mark.parametrize("tool", TOOLS, ids=("ee_link", "tool0"))
def test_numpy_fk_equals_pinocchio_fk(robot: object, tool: ToolOffset) -> None:
    model = Ur3Model(tool, robot=robot)  # type: ignore[arg-type]
    rng = np.random.default_rng(20261125)
    for q in rng.uniform(-2 * math.pi, 2 * math.pi, size=(200, 6)):
        for frame in FRAMES:
            H_pin = model.fk(q, frame).homogeneous
            H_np = model.fk_matrix(q, frame)
            assert np.max(np.abs(H_np[:3, 3] - H_pin[:3, 3])) <= 1e-12, (frame, q)
            assert np.max(np.abs(H_np[:3, :3] - H_pin[:3, :3])) <= 1e-12, (frame, q)
    assert np.allclose(model.H_tcp_tool0, model.T_flange_tcp("tool0").inverse().homogeneous, rtol=0.0, atol=1e-15)


def test_chain_reads_the_ur3_joints_and_frames() -> None:
    chain = parse_chain(urdf_text(TOOLS[0]))
    assert chain.joint_names == JOINT_NAMES
    assert set(FRAMES) <= set(chain.frames)
    assert chain.frames["tcp"][0] == chain.frames["tool0"][0] == 6  # fixed to the last joint's link
    assert chain.frames["base_link"][0] == 0


def test_rotations_are_proper() -> None:
    rng = np.random.default_rng(3)
    for rpy in rng.uniform(-math.pi, math.pi, size=(50, 3)):
        R = rpy_matrix(*rpy)
        assert np.allclose(R @ R.T, np.eye(3), atol=1e-15) and math.isclose(np.linalg.det(R), 1.0, abs_tol=1e-14)
        assert np.allclose(R, rpy_matrix(0, 0, rpy[2]) @ rpy_matrix(0, rpy[1], 0) @ rpy_matrix(rpy[0], 0, 0),
                           atol=1e-15)
    axis = np.array([1.0, 2.0, -0.5]) / math.sqrt(5.25)
    T = axis_rotation(axis, 0.7)
    assert np.allclose(T[:3, :3] @ axis, axis, atol=1e-15)  # the axis is fixed
    assert math.isclose(np.trace(T[:3, :3]), 1 + 2 * math.cos(0.7), abs_tol=1e-15)
    assert np.allclose(rigid_inverse(T) @ T, np.eye(4), atol=1e-15)


def test_a_branching_or_prismatic_urdf_is_refused() -> None:
    text = urdf_text(TOOLS[0]).replace('type="revolute"', 'type="prismatic"', 1)
    with pytest.raises(Ur3HanoiError, match="prismatic"):
        parse_chain(text)
    with pytest.raises(Ur3HanoiError, match="not XML"):
        parse_chain("<robot")
