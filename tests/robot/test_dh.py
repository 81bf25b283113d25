"""ur3hanoi.robot.dh: the one DH matrix is Rz(theta) Tz(d) Tx(a) Rx(alpha) (against the four elementary transforms
written out here), its scalar and batched forms agree, and the FK of a DH table composes it."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.support.se3 import rot_x, rot_z, trans
from ur3hanoi.robot.dh import dh_fk, dh_frames, dh_link, dh_matrix
from ur3hanoi.robot.registry import UR3, UR3E, RobotDescription

ANGLE = st.floats(-2 * math.pi, 2 * math.pi)
LENGTH = st.floats(-1.0, 1.0)


@settings(max_examples=200, deadline=None)
@given(ANGLE, LENGTH, LENGTH, ANGLE)
def test_dh_matrix_is_the_four_elementary_transforms(theta: float, d: float, a: float, alpha: float) -> None:
    expected = rot_z(theta) @ trans(0, 0, d) @ trans(a, 0, 0) @ rot_x(alpha)
    np.testing.assert_allclose(dh_matrix(theta, d, a, alpha), expected, rtol=0.0, atol=1e-15)


def test_batched_form_equals_the_scalar_form() -> None:
    rng = np.random.default_rng(11)
    thetas = rng.uniform(-2 * math.pi, 2 * math.pi, 300)
    for i in range(6):
        batch = dh_link(thetas, i, UR3E.dh)
        assert batch.shape == (300, 4, 4)
        for theta, A in zip(thetas, batch, strict=True):
            # math.cos (scalar) and NumPy's cos (batched) may differ in the last bit.
            np.testing.assert_allclose(A, dh_link(float(theta), i, UR3E.dh), rtol=0.0, atol=4e-16)


@pytest.mark.parametrize("robot", [UR3, UR3E], ids=lambda r: r.name)
def test_fk_composes_the_joints_and_its_frames_are_the_partial_products(robot: RobotDescription) -> None:
    rng = np.random.default_rng(12)
    qs = rng.uniform(-2 * math.pi, 2 * math.pi, size=(40, 6))
    H = np.eye(4)
    H[:3, 3] = (0.1, -0.2, 0.3)
    frames = dh_frames(qs, robot.dh, H)
    batch = dh_fk(qs, robot.dh)
    for n, q in enumerate(qs):
        T = np.eye(4)
        for i in range(6):
            T = T @ rot_z(q[i]) @ trans(0, 0, robot.dh.d[i]) @ trans(robot.dh.a[i], 0, 0) @ rot_x(robot.dh.alpha[i])
            np.testing.assert_allclose(frames[i][n], H @ T, rtol=0.0, atol=1e-14)
        np.testing.assert_allclose(batch[n], T, rtol=0.0, atol=1e-14)


def test_batched_fk_equals_single() -> None:
    rng = np.random.default_rng(3)
    qs = rng.uniform(-math.pi, math.pi, size=(50, 6))
    batch = dh_fk(qs)
    assert batch.shape == (50, 4, 4)
    for q, T in zip(qs, batch, strict=True):
        assert np.array_equal(dh_fk(q), T)
    assert np.array_equal(dh_fk(qs[0]), dh_fk(qs[0], UR3.dh))  # the UR3 by default
