"""The Denavit-Hartenberg transform of one joint, and forward kinematics from a DH table, in NumPy (no Pinocchio).

Standard DH (the convention of Universal Robots' published tables): joint i moves DH frame i-1 to frame i by
``Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. The tables themselves live in :mod:`ur3hanoi.robot.registry`
(``RobotDescription.dh``); :func:`dh_matrix` is the one place the product is written out, for a single angle (the
closed-form IK's branch test, the constant DH frames of the URDF generator and the clearance check) and for a batch
of angles (FK over whole trajectories without a per-sample call).
"""

from __future__ import annotations

import math

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.registry import N_JOINTS, UR3, DHParameters


def dh_matrix(theta: float | FloatArray, d: float, a: float, alpha: float) -> FloatArray:
    """``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` [rad, m]: a 4x4 matrix for a scalar ``theta``, (N, 4, 4) for shape (N,).

    A scalar angle takes its cosine and sine from :mod:`math` (libm, cheaper per call than NumPy's ufuncs on one
    number), an array from NumPy's ufuncs: each path gives the same bits on every call, which keeps a table and the
    checks built on it reproducible.
    """
    ca, sa = math.cos(alpha), math.sin(alpha)
    if np.ndim(theta) == 0:
        ct, st = math.cos(theta), math.sin(theta)
        return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d],
                         [0.0, 0.0, 0.0, 1.0]])
    cv, sv = np.cos(theta), np.sin(theta)
    A = np.zeros((len(cv), 4, 4))
    A[:, 0, 0], A[:, 0, 1], A[:, 0, 2], A[:, 0, 3] = cv, -sv * ca, sv * sa, a * cv
    A[:, 1, 0], A[:, 1, 1], A[:, 1, 2], A[:, 1, 3] = sv, cv * ca, -cv * sa, a * sv
    A[:, 2, 1], A[:, 2, 2], A[:, 2, 3] = sa, ca, d
    A[:, 3, 3] = 1.0
    return A


def dh_link(theta: float | FloatArray, i: int, dh: DHParameters) -> FloatArray:
    """:func:`dh_matrix` of joint ``i`` (0-based) of the table ``dh`` at angle(s) ``theta`` [rad]."""
    return dh_matrix(theta, dh.d[i], dh.a[i], dh.alpha[i])


def dh_frames(q: FloatArray, dh: DHParameters, H_base_root: FloatArray) -> list[FloatArray]:
    """The DH frames 1..6 at the configurations ``q`` [rad] of shape (N, 6): six (N, 4, 4) arrays,
    ``H_base_root A_1(q_1) .. A_i(q_i)``, where ``H_base_root`` (4x4) is the pose of DH frame 0 (the controller
    ``base``) in the frame the results are wanted in."""
    T = np.broadcast_to(H_base_root, (len(q), 4, 4))
    out = []
    for i in range(N_JOINTS):
        T = T @ dh_link(q[:, i], i, dh)
        out.append(T)
    return out


_IDENTITY = np.eye(4)


def dh_fk(q: FloatArray, dh: DHParameters = UR3.dh) -> FloatArray:
    """Forward kinematics from the DH table ``dh`` (default the UR3's): the pose of the flange (``tool0``, the last
    DH frame) in the controller ``base`` frame.

    ``q`` [rad] of shape (6,) gives a 4x4 matrix; shape (N, 6) gives (N, 4, 4) (batched, for checks over whole
    trajectories without a per-sample Pinocchio call).
    """
    q = np.asarray(q, dtype=float)
    T = dh_frames(q.reshape(-1, N_JOINTS), dh, _IDENTITY)[-1]
    return T[0] if q.ndim == 1 else T


__all__ = ["dh_fk", "dh_frames", "dh_link", "dh_matrix"]
