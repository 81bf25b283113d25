"""UR3 model: URDF link lengths, frames, datasheet limits, and Pinocchio FK vs the DH table."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot.dh import dh_fk
from ur3hanoi.robot.model import Q_HOME_LAB, T_BASELINK_BASE, JointLimits, Ur3Model, load_ur3
from ur3hanoi.robot.urdf import JOINT_NAMES, ToolOffset, urdf_path, urdf_text

LAB_TOOL = ToolOffset("ee_link", (0.059, 0.0535, 0.0), (0.0, math.pi / 2, 0.0))


def test_urdf_is_the_ur3_by_path() -> None:
    path = urdf_path()
    assert path.name == "ur3_robot.urdf"
    assert path.is_file()


def test_model_has_ur3_joints_and_frames() -> None:
    m = load_ur3()
    assert tuple(m.model.names[1:]) == JOINT_NAMES
    assert m.nq == 6
    for frame in ("base", "base_link", "tool0", "ee_link", "tcp"):
        assert m.model.existFrame(frame)


def test_ur5_urdf_is_rejected(monkeypatch: pytest.MonkeyPatch) -> None:
    ur5 = urdf_path().with_name("ur5_robot.urdf")
    monkeypatch.setattr("ur3hanoi.robot.urdf.urdf_path", lambda: ur5)
    urdf_text.cache_clear()
    try:
        with pytest.raises(Ur3HanoiError, match="link length d1"):
            Ur3Model()
    finally:
        urdf_text.cache_clear()


def test_fk_base_to_tool0_matches_dh_on_1000_random_configurations() -> None:
    m = load_ur3()
    rng = np.random.default_rng(20261122)
    worst = 0.0
    for q in rng.uniform(-2 * math.pi, 2 * math.pi, size=(1000, 6)):
        worst = max(worst, float(np.abs(m.fk(q, "tool0").homogeneous - dh_fk(q)).max()))
    assert worst < 1e-9


def test_base_frame_is_base_link_rotated_pi_about_z() -> None:
    m = load_ur3()
    pin.framesForwardKinematics(m.model, m.data, np.zeros(6))
    T_baselink_base = m.data.oMf[m.frame_ids["base"]]
    assert np.allclose(T_baselink_base.homogeneous, T_BASELINK_BASE.homogeneous, atol=1e-10)
    # A point straight ahead in `base` (+x) is behind in `base_link` (-x).
    assert np.allclose(T_BASELINK_BASE.act(np.array([1.0, 0.0, 0.0])), [-1.0, 0.0, 0.0])


def test_home_tool0_pose_in_base() -> None:
    # Measured in base_link: (-0.2466, 0.20242, 0.31365); `base` flips x and y.
    T = load_ur3().fk(np.array(Q_HOME_LAB), "tool0")
    assert np.allclose(T.translation, [0.246598, -0.202420, 0.31365], atol=1e-5)
    assert np.allclose(T.rotation[:, 2], [0.0, 0.0, -1.0], atol=1e-9)  # pointing down


def test_tcp_frame_is_the_tool_offset() -> None:
    m = load_ur3(LAB_TOOL)
    T_ee_tcp = m.T_flange_tcp("ee_link")
    assert np.allclose(T_ee_tcp.translation, LAB_TOOL.xyz, atol=1e-12)
    # The suction direction (tcp z) is ee_link's x axis, which is tool0's z axis.
    assert np.allclose(T_ee_tcp.rotation[:, 2], [1.0, 0.0, 0.0], atol=1e-12)
    T_tool0_tcp = m.T_flange_tcp("tool0")
    assert np.allclose(T_tool0_tcp.rotation[:, 2], [0.0, 0.0, 1.0], atol=1e-10)
    assert np.isclose(T_tool0_tcp.translation[2], 0.059, atol=1e-10)


def test_datasheet_limits_not_urdf_values() -> None:
    lim = JointLimits.ur3()
    assert lim.v_max == pytest.approx((math.pi,) * 3 + (2 * math.pi,) * 3)
    assert lim.q_max == pytest.approx((2 * math.pi,) * 6)
    urdf_velocities = (2.16, 2.16, 3.15, 3.2, 3.2, 3.2)
    assert not np.allclose(lim.v_max, urdf_velocities)
    assert JointLimits.ur3(elbow_limit=math.pi).q_max[2] == pytest.approx(math.pi)
    with pytest.raises(Ur3HanoiError, match="elbow_limit"):
        JointLimits.ur3(elbow_limit=-1.0)


def test_within_position() -> None:
    lim = JointLimits.ur3(elbow_limit=math.pi)
    assert lim.within_position(np.zeros(6))
    assert not lim.within_position(np.array([0, 0, 3.5, 0, 0, 0.0]))


def test_unknown_frame_error_lists_frames() -> None:
    with pytest.raises(Ur3HanoiError, match="expected one of"):
        load_ur3().fk(np.zeros(6), "flange")

