"""ur3hanoi.robot.ik_solvers: the numerical solvers converge on their own from a perturbed seed, an unknown solver
is refused, and pose errors are measured accurately down to tiny angles."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from tests.robot.conftest import HOME_BRANCH
from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot.ik import analytic_ik
from ur3hanoi.robot.ik_solvers import SOLVERS, as_matrix, make_solver, pose_errors, rotation_angle
from ur3hanoi.robot.model import Ur3Model, load_ur3


@pytest.mark.parametrize("solver_name", SOLVERS)
def test_numerical_solver_converges_from_a_perturbed_seed(robot: Ur3Model, downward_poses: list[pin.SE3],
                                                          solver_name: str) -> None:
    """The numerical solvers do real work: from a seed 0.1 rad off they converge to 1e-9 on their own."""
    solver = make_solver(solver_name, robot)
    rng = np.random.default_rng(5)
    T_tcp_tool0 = robot.T_flange_tcp("tool0").inverse()
    converged = 0
    for T in downward_poses[:100]:
        q_true = analytic_ik(T * T_tcp_tool0, only=HOME_BRANCH)[HOME_BRANCH]
        res = solver.solve(T, q_true + rng.normal(0.0, 0.1, 6))
        assert res.iterations > 1
        converged += res.converged
    assert converged >= 98


def test_unknown_solver() -> None:
    with pytest.raises(Ur3HanoiError, match="expected one of"):
        make_solver("ikfast", load_ur3())


@pytest.mark.parametrize("angle", [1e-13, 1e-9, 1e-4, 0.5, 3.0])
def test_pose_errors_are_the_distance_and_the_rotation_angle(angle: float) -> None:
    rng = np.random.default_rng(8)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    A = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(size=3))
    B = A * pin.SE3(pin.exp3(angle * axis), np.array([3e-10, 0.0, -4e-10]))
    dp, dr = pose_errors(A, B.homogeneous)  # a pin.SE3 and a 4x4 matrix
    assert dp == pytest.approx(5e-10, rel=1e-5)  # the offset (3, 0, -4) x 1e-10 m in B's own frame
    assert dr == pytest.approx(angle, rel=1e-6)
    assert rotation_angle(as_matrix(B)[:3, :3].T @ as_matrix(A)[:3, :3]) == pytest.approx(angle, rel=1e-6)
    assert math.isclose(rotation_angle(np.eye(3)), 0.0, abs_tol=0.0)
