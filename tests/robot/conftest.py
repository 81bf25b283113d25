"""Fixtures of the IK tests (test_ik.py, test_ik_solvers.py): the lab_sim arm and 200 seeded downward poses."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest

from ur3hanoi.robot.ik import analytic_ik, branch_of
from ur3hanoi.robot.model import Q_HOME_LAB, Ur3Model, load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import R_world_tcp_down

Q_HOME = np.array(Q_HOME_LAB)
HOME_BRANCH = branch_of(Q_HOME)


@pytest.fixture(scope="module")
def robot(lab_sim: Station) -> Ur3Model:
    return load_ur3(lab_sim.tool, lab_sim.limits)


@pytest.fixture(scope="module")
def downward_poses(robot: Ur3Model) -> list[pin.SE3]:
    """200 seeded, reachable TCP poses pointing straight down with random yaw (targets in `base`)."""
    rng = np.random.default_rng(1234)
    T_tcp_tool0 = robot.T_flange_tcp("tool0").inverse()
    poses: list[pin.SE3] = []
    while len(poses) < 200:
        p = np.array([rng.uniform(-0.45, 0.45), rng.uniform(-0.45, 0.45), rng.uniform(-0.05, 0.35)])
        T = pin.SE3(R_world_tcp_down(rng.uniform(-math.pi, math.pi)), p)
        if HOME_BRANCH in analytic_ik(T * T_tcp_tool0, only=HOME_BRANCH):
            poses.append(T)
    return poses
