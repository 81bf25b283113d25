"""NumPy FK of the URDF chain (:mod:`ur3hanoi.robot.chain`) against Pinocchio's FK, the reference model."""

from __future__ import annotations

import math
import platform

import numpy as np
import pytest

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot.chain import axis_rotation, parse_chain, rigid_inverse, rpy_matrix
from ur3hanoi.robot.model import Ur3Model
from ur3hanoi.robot.registry import UR3, UR3E
from ur3hanoi.robot.urdf import JOINT_NAMES, ToolOffset, urdf_text

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


def test_a_chain_with_a_base_reports_in_it() -> None:
    """The model's chain reports in the controller ``base``: the root link's FK, then the base's pose of the root."""
    from ur3hanoi.robot.model import H_BASE_BASELINK

    model = Ur3Model(TOOLS[1])
    in_root = parse_chain(model.urdf)
    qs = np.random.default_rng(4).uniform(-2 * math.pi, 2 * math.pi, size=(20, 6))
    for frame in FRAMES:
        np.testing.assert_array_equal(model.chain.fk(qs, frame), H_BASE_BASELINK @ in_root.fk(qs, frame))
        np.testing.assert_array_equal(model.chain.fk(qs[3], frame), model.fk_matrix(qs[3], frame))
    assert not np.allclose(in_root.fk(qs, "tcp"), model.chain.fk(qs, "tcp"))


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


# Pinocchio's order of operations, evaluated without fused multiply-adds (x86-64 builds): equal bit for bit here; a
# build that contracts a*b+c into one rounding (some aarch64 compilers) may differ in the last bit or two.
ULPS = 1e-15


def test_constants_are_pinocchios_to_the_last_bit() -> None:
    """What a table's IK reads is computed in Pinocchio's own order of operations: the joint placements, the TCP
    offset, the base pose's rotation are Pinocchio's (bit for bit on this build: a table, and every plan built on
    it, is the same with or without Pinocchio imported)."""
    import pinocchio as pin

    rng = np.random.default_rng(7)
    tools = [*TOOLS, *(ToolOffset(str(rng.choice(["ee_link", "tool0"])), tuple(rng.uniform(-0.1, 0.1, 3)),
                                  tuple(rng.uniform(-3.2, 3.2, 3))) for _ in range(10))]
    for robot in (UR3, UR3E):
        for tool in tools:
            model = Ur3Model(tool, robot=robot)  # type: ignore[arg-type]
            for i in range(6):
                np.testing.assert_allclose(model.chain.joint_placements[i],
                                           model.model.jointPlacements[i + 1].homogeneous, rtol=0.0, atol=ULPS)
            np.testing.assert_allclose(model.H_tcp_tool0, model.T_flange_tcp("tool0").inverse().homogeneous,
                                       rtol=0.0, atol=ULPS)
            for flange in ("tool0", "ee_link"):
                np.testing.assert_allclose(model.H_flange_tcp(flange), model.T_flange_tcp(flange).homogeneous,
                                           rtol=0.0, atol=ULPS)
    for rpy in rng.uniform(-3.5, 3.5, size=(500, 3)):
        np.testing.assert_allclose(rpy_matrix(*rpy), pin.rpy.rpyToMatrix(*rpy), rtol=0.0, atol=ULPS)


def test_table_equals_the_pinocchio_pose_chain_bit_for_bit(lab_real: object) -> None:
    """generate_table (NumPy poses) gives the closed form fed by Pinocchio's SE3 poses (the very bits on this build,
    see ULPS), also on a tilted base."""
    import dataclasses

    from ur3hanoi.robot.ik import analytic_ik, branch_of, nearest_equivalent
    from ur3hanoi.robot.model import load_ur3
    from ur3hanoi.station.grid import T_base_tcp
    from ur3hanoi.tables.ik_table import generate_table

    for station in (lab_real, dataclasses.replace(lab_real, base_rpy=(0.003, -0.002, 0.12))):  # type: ignore[type-var]
        robot = load_ur3(station.tool, station.limits, station.robot)
        table = generate_table(station).q
        home = branch_of(station.q_home_array)
        for t in range(station.n_towers):
            for h in range(station.n_heights):
                for k in (0, 1):
                    T = T_base_tcp(station, t, h, k) * robot.T_flange_tcp("tool0").inverse()
                    q = nearest_equivalent(analytic_ik(T, only=home)[home], station.q_home_array, station.limits)
                    np.testing.assert_allclose(table[t, h, k], q, rtol=0.0, atol=1e-14)
                    if platform.machine() in ("x86_64", "AMD64"):  # baseline x86-64 has no FMA: the same bits
                        np.testing.assert_array_equal(table[t, h, k], q)
