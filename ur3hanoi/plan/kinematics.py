"""Where the suction point is and how it accelerates, in the world frame: the UR3's forward kinematics in closed
form, vectorised over trajectory samples (the legs are verified with it at 1 kHz, the checks use it at every sample).
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station


@lru_cache(maxsize=32)
def _tcp_frames(station: Station) -> tuple[tuple[float, float, float], FloatArray, FloatArray]:
    """The suction point in the flange frame (tool0) [m], and the world rotation and translation of ``base``."""
    t = load_ur3(station.tool, station.limits, station.robot).H_flange_tcp("tool0")[:3, 3]
    H_wb = station.H_world_base
    return (float(t[0]), float(t[1]), float(t[2])), H_wb[:3, :3].copy(), H_wb[:3, 3].copy()


def tcp_positions_world(station: Station, q: FloatArray) -> FloatArray:
    """World position [m] of the suction point at every row of ``q`` (N, 6): the UR3's DH forward kinematics in
    closed form (the chain of ``dh_fk`` multiplied out: joints 2-4 are parallel, so they add up to planar angles).

    Same kinematics as ``Ur3Model.fk(q, "tcp")`` (the URDF and the DH table agree to ~1e-11 m), without a
    per-sample Pinocchio call, and several times cheaper than the batched 4x4 products of ``dh_fk``: the vertical
    line of every leg is checked with it at 1 kHz.
    """
    q = np.asarray(q, dtype=float).reshape(-1, 6)
    (tx, ty, tz), R_wb, p_wb = _tcp_frames(station)
    d1, _, _, d4, d5, d6 = station.robot.dh.d
    a2, a3 = station.robot.dh.a[1], station.robot.dh.a[2]
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    q23 = q[:, 1] + q[:, 2]
    q234 = q23 + q[:, 3]
    c234, s234 = np.cos(q234), np.sin(q234)
    c5, s5 = np.cos(q[:, 4]), np.sin(q[:, 4])
    c6, s6 = np.cos(q[:, 5]), np.sin(q[:, 5])
    # Frame 1 (after joint 1 and its alpha = pi/2): joints 2-4 rotate about its z axis. Tool offset rotated by
    # Rz(q234) Ry(-q5) Rz(q6).
    wx, wy = c6 * tx - s6 * ty, s6 * tx + c6 * ty
    ux, uz = c5 * wx - s5 * tz, s5 * wx + c5 * tz
    x = a2 * np.cos(q[:, 1]) + a3 * np.cos(q23) + d5 * s234 - d6 * s5 * c234 + c234 * ux - s234 * wy
    y = a2 * np.sin(q[:, 1]) + a3 * np.sin(q23) - d5 * c234 - d6 * s5 * s234 + s234 * ux + c234 * wy
    z = d4 + d6 * c5 + uz
    p_base = np.stack([c1 * x + s1 * z, s1 * x - c1 * z, y + d1], axis=1)
    return p_base @ R_wb.T + p_wb




def tcp_accelerations_world(station: Station, q: FloatArray, qd: FloatArray, qdd: FloatArray,
                            h: float = 1e-3) -> FloatArray:
    """World acceleration [m/s^2] of the suction point at every row of ``q``/``qd``/``qdd`` (N, 6): the second
    difference of the forward kinematics along each sample's own second-order Taylor path ``q + s qd + s^2/2 qdd``
    (s = +-h [s]), exact to O(h^2); no finite difference across samples."""
    q, qd, qdd = (np.asarray(x, dtype=float).reshape(-1, 6) for x in (q, qd, qdd))
    half = 0.5 * h * h * qdd
    plus = tcp_positions_world(station, q + h * qd + half)
    minus = tcp_positions_world(station, q - h * qd + half)
    return (plus - 2.0 * tcp_positions_world(station, q) + minus) / (h * h)
