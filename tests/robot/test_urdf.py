"""ur3hanoi.robot.urdf and the UR3e through the toolkit's kinematics: the generated URDF's FK equals an independent
DH FK to 1e-9 m, UR's published centres of mass land where the DH table puts them, and the closed-form IK
generalised by the DH table solves UR3e poses to 1e-9 m (the UR3's table would miss them by centimetres)."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from tests.support.se3 import rot_x, rot_z, trans
from ur3hanoi.robot.dh import dh_fk
from ur3hanoi.robot.ik import analytic_ik, branch_of, wrap_angle
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.robot.registry import UR3, UR3E, RobotDescription
from ur3hanoi.robot.urdf import JOINT_NAMES, link_inertias, urdf_from_dh


def independent_dh(q: np.ndarray, r: RobotDescription, upto: int = 6) -> np.ndarray:
    """Textbook standard DH written out as four elementary transforms per joint (not the package's fused form)."""
    T = np.eye(4)
    for i in range(upto):
        T = T @ rot_z(q[i]) @ trans(0, 0, r.dh.d[i]) @ trans(r.dh.a[i], 0, 0) @ rot_x(r.dh.alpha[i])
    return T


def test_generated_ur3e_urdf_fk_equals_independent_dh_fk() -> None:
    model = load_ur3(None, None, UR3E)
    assert tuple(model.model.names[1:]) == JOINT_NAMES
    rng = np.random.default_rng(21)
    worst_p = worst_r = 0.0
    for q in rng.uniform(-2 * math.pi, 2 * math.pi, (500, 6)):
        T = model.fk(q, "tool0").homogeneous
        ref = independent_dh(q, UR3E)
        worst_p = max(worst_p, float(np.linalg.norm(T[:3, 3] - ref[:3, 3])))
        worst_r = max(worst_r, float(np.abs(T[:3, :3] - ref[:3, :3]).max()))
        assert np.abs(dh_fk(q, UR3E.dh) - ref).max() < 1e-12
    assert worst_p < 1e-9 and worst_r < 1e-9
    # The UR3's table is not the UR3e's: the same q lands centimetres away.
    q = np.radians([120, -90, 90, -90, -90, 0])
    assert np.linalg.norm(independent_dh(q, UR3)[:3, 3] - independent_dh(q, UR3E)[:3, 3]) > 0.02


def test_published_centres_of_mass_are_where_the_dh_table_puts_them() -> None:
    model = pin.buildModelFromXML(urdf_from_dh(UR3E))
    data = model.createData()
    T_baselink_base = np.diag([-1.0, -1.0, 1.0, 1.0])
    rng = np.random.default_rng(4)
    for q in rng.uniform(-math.pi, math.pi, (20, 6)):
        pin.forwardKinematics(model, data, q)
        for i in range(6):
            inertia = model.inertias[i + 1]
            assert inertia.mass == pytest.approx(UR3E.masses[i], abs=1e-12)
            com = data.oMi[i + 1].act(inertia.lever)
            ref = T_baselink_base @ independent_dh(q, UR3E, i + 1) @ np.array([*UR3E.com_dh[i], 1.0])
            assert np.linalg.norm(com - ref[:3]) < 1e-9
    assert all(min(li.diag) > 0 for li in link_inertias(UR3E))


def test_closed_form_ik_generalised_by_the_dh_table_solves_ur3e_poses() -> None:
    rng = np.random.default_rng(7)
    solved = 0
    for q in rng.uniform(-math.pi, math.pi, (200, 6)):
        if abs(math.sin(q[4])) < 0.05:
            continue
        T = independent_dh(q, UR3E)
        sols = analytic_ik(T, dh=UR3E.dh)
        assert branch_of(q, UR3E.dh) in sols
        assert np.abs(wrap_angle(sols[branch_of(q, UR3E.dh)] - q)).max() < 1e-8
        for qs in sols.values():
            assert np.linalg.norm(independent_dh(qs, UR3E)[:3, 3] - T[:3, 3]) < 1e-9
        # The UR3's constants (the old hard-wired IK) miss the UR3e pose.
        for qs in analytic_ik(T).values():
            assert np.linalg.norm(independent_dh(qs, UR3E)[:3, 3] - T[:3, 3]) > 1e-3
        solved += 1
    assert solved > 150
