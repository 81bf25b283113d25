"""Homogeneous transforms written out by hand, as independent references for the kinematics tests."""

from __future__ import annotations

import math

import numpy as np


def rot_z(t: float) -> np.ndarray:
    """Rotation by ``t`` [rad] about z, 4x4."""
    c, s = math.cos(t), math.sin(t)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def rot_x(t: float) -> np.ndarray:
    """Rotation by ``t`` [rad] about x, 4x4."""
    c, s = math.cos(t), math.sin(t)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def trans(x: float, y: float, z: float) -> np.ndarray:
    """Translation by (x, y, z) [m], 4x4."""
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T
