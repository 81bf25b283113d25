"""The tower grid in Cartesian space: suction-point (TCP) targets and block positions of a station.

Indexing follows the lab: ``tower`` 0..n_towers-1, ``height`` 0 (bottom) .. n_heights-1, and ``k`` 0 = the
contact ("on") pose, 1 = the pose "in the air" above it (the order of the course's ``lab2_data.yaml``).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.station.calibration import Station

if TYPE_CHECKING:
    import pinocchio as pin

ON, ABOVE = 0, 1
POSE_NAMES: tuple[str, str] = ("on", "above")


def pose_label(tower: int, height: int, k: int) -> str:
    """How people name ``Q[tower][height][k]`` (0-based indices): ``pose_label(0, 1, 1) == "tower 1 height 2
    above"``. Towers and heights are numbered from 1 wherever a person reads them."""
    return f"tower {tower + 1} height {height + 1} {POSE_NAMES[k]}"


def R_world_tcp_down(yaw: float) -> FloatArray:
    """TCP orientation with z pointing straight down and x along ``(cos yaw, sin yaw, 0)`` in world."""
    c, s = math.cos(yaw), math.sin(yaw)
    # Rz(yaw) @ Rx(pi): x keeps its heading, y and z flip.
    return np.array([[c, s, 0.0], [s, -c, 0.0], [0.0, 0.0, -1.0]])


def check_index(station: Station, tower: int, height: int, k: int = ON) -> None:
    """Raise a one-line error naming the valid ranges when an index is outside the station's grid."""
    if not 0 <= tower < station.n_towers:
        raise Ur3HanoiError(f"tower index {tower} is outside the grid: expected 0..{station.n_towers - 1}")
    if not 0 <= height < station.n_heights:
        raise Ur3HanoiError(f"height index {height} is outside the grid: expected 0..{station.n_heights - 1}")
    if k not in (ON, ABOVE):
        raise Ur3HanoiError(f"pose index {k} is invalid: expected 0 (on) or 1 (above)")


def contact_point_world(station: Station, tower: int, height: int) -> FloatArray:
    """Suction point [m, world] of the contact ("on") pose at (tower, height)."""
    check_index(station, tower, height)
    return np.asarray(station.tower_origins[tower], dtype=float) + height * np.asarray(station.height_step)


def H_world_tcp(station: Station, tower: int, height: int, k: int) -> FloatArray:
    """Target pose of the suction point (TCP) in world for (tower, height, k), as a 4x4 matrix (NumPy only; in
    ``base``: ``robot_chain.se3_act_inv(station.H_world_base, H)``, :func:`T_base_tcp`'s numbers bit for bit)."""
    check_index(station, tower, height, k)
    p = contact_point_world(station, tower, height)
    if k == ABOVE:
        p = p + np.array([0.0, 0.0, station.approach])
    H = np.eye(4)
    H[:3, :3] = R_world_tcp_down(station.tool_yaw)
    H[:3, 3] = p
    return H


def T_world_tcp(station: Station, tower: int, height: int, k: int) -> pin.SE3:
    """Target pose of the suction point (TCP) in world for (tower, height, k)."""
    import pinocchio as pin

    return pin.SE3(H_world_tcp(station, tower, height, k))


def T_base_tcp(station: Station, tower: int, height: int, k: int) -> pin.SE3:
    """Target pose of the TCP in the controller ``base`` frame (what IK solves for)."""
    return station.T_world_base.actInv(T_world_tcp(station, tower, height, k))


def grid_targets_world(station: Station) -> FloatArray:
    """All TCP targets as an array ``[tower, height, k, 4, 4]`` of homogeneous world poses."""
    out = np.empty((station.n_towers, station.n_heights, 2, 4, 4))
    for t in range(station.n_towers):
        for h in range(station.n_heights):
            for k in (ON, ABOVE):
                out[t, h, k] = H_world_tcp(station, t, h, k)
    return out


def block_center_world(station: Station, tower: int, height: int) -> FloatArray:
    """Centre [m, world] of the block resting in slot (tower, height) when the suction point is at contact.

    The block's top face is ``contact_depth`` above the contact suction point.
    """
    p = contact_point_world(station, tower, height)
    return p + np.array([0.0, 0.0, station.contact_depth - 0.5 * station.block_size])


def table_z(station: Station) -> float:
    """World height [m] of the table surface: the bottom face of the height-0 block of tower 0."""
    return float(block_center_world(station, 0, 0)[2] - 0.5 * station.block_size)


def block_xy_pos(station: Station) -> list[list[list[float]]]:
    """Block positions ``[tower][height] -> [x, y]`` [m, world], as the course's spawn script uses them."""
    return [
        [[float(v) for v in block_center_world(station, t, h)[:2]] for h in range(station.n_heights)]
        for t in range(station.n_towers)
    ]
