"""Forward kinematics of a robot's URDF serial chain in plain NumPy: Pinocchio's ``oMf`` without Pinocchio.

A table of a shipped station needs FK only to measure the closed-form IK's residual (18 poses); importing Pinocchio
for that costs more than the whole rest of ``ur3hanoi tables``. :func:`parse_chain` reads the joints of a URDF (the
same text Pinocchio builds its model from, with the ``tcp`` frame), merges fixed joints into the placements the way
Pinocchio does (a frame's placement in its parent joint's frame), and :meth:`UrdfChain.fk` composes them: the
result equals Pinocchio's ``framesForwardKinematics`` to rounding (tests/test_robot_chain.py compares them on seeded
random configurations). Pinocchio stays the reference model of :class:`ur3hanoi.robot.Ur3Model` (Jacobians,
collision geometry, the numerical IK refiners).

Frames: every placement is in the URDF root link's frame (``base_link`` for the UR URDFs, whose ``world`` link is
fixed to it at the identity).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import Ur3HanoiError


def rpy_matrix(roll: float, pitch: float, yaw: float) -> FloatArray:
    """URDF roll-pitch-yaw [rad] (fixed axes x, y, z) as a rotation matrix: ``Rz(yaw) Ry(pitch) Rx(roll)``."""
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    return np.array([[cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
                     [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
                     [-sp, cp * sr, cp * cr]])


def rigid_inverse(T: FloatArray) -> FloatArray:
    """Inverse of a 4x4 rigid transform: ``(R^T, -R^T p)``."""
    out = np.eye(4)
    out[:3, :3] = T[:3, :3].T
    out[:3, 3] = -(T[:3, :3].T @ T[:3, 3])
    return out


def _placement(xyz: str | None, rpy: str | None) -> FloatArray:
    T = np.eye(4)
    if rpy:
        T[:3, :3] = rpy_matrix(*(float(v) for v in rpy.split()))
    if xyz:
        T[:3, 3] = [float(v) for v in xyz.split()]
    return T


def axis_rotation(axis: FloatArray, angle: float) -> FloatArray:
    """4x4 rotation by ``angle`` [rad] about the unit ``axis`` (Rodrigues; exact for the coordinate axes)."""
    x, y, z = axis.tolist()
    c, s = math.cos(angle), math.sin(angle)
    T = np.eye(4)
    if (x, y, z) == (0.0, 0.0, 1.0):
        T[0, 0], T[0, 1], T[1, 0], T[1, 1] = c, -s, s, c
    elif (x, y, z) == (0.0, 1.0, 0.0):
        T[0, 0], T[0, 2], T[2, 0], T[2, 2] = c, s, -s, c
    elif (x, y, z) == (1.0, 0.0, 0.0):
        T[1, 1], T[1, 2], T[2, 1], T[2, 2] = c, -s, s, c
    else:
        C = 1.0 - c
        T[:3, :3] = [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
                     [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
                     [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]
    return T


@dataclass(frozen=True)
class UrdfChain:
    """A serial chain of revolute joints read from a URDF.

    Attributes:
        joint_names: the revolute joints from the root outwards.
        joint_placements: each joint's frame at q = 0 in its parent joint's frame (the root link for the first),
            4x4; Pinocchio's ``model.jointPlacements``.
        axes: each joint's unit axis in its own frame.
        frames: link name -> (index of its parent joint, 0 = the root link, i = ``joint_names[i - 1]``; its
            placement in that joint's frame, 4x4); Pinocchio's ``model.frames[...].placement``.
    """

    joint_names: tuple[str, ...]
    joint_placements: tuple[FloatArray, ...]
    axes: tuple[FloatArray, ...]
    frames: dict[str, tuple[int, FloatArray]]

    def fk(self, q: FloatArray, frame: str) -> FloatArray:
        """4x4 pose of link ``frame`` in the root link's frame at joint angles ``q`` [rad]."""
        try:
            parent, placement = self.frames[frame]
        except KeyError:
            raise Ur3HanoiError(f"frame {frame!r} is unknown: expected one of {sorted(self.frames)}") from None
        T = np.eye(4)
        for i, angle in enumerate(np.asarray(q, dtype=float).tolist()[:parent]):
            T = T @ self.joint_placements[i] @ axis_rotation(self.axes[i], angle)
        return T @ placement


def parse_chain(urdf: str) -> UrdfChain:
    """The serial chain of ``urdf`` (text): its revolute joints from the root link, every link as a frame.

    Raises:
        Ur3HanoiError: the text is not a URDF, has joints of another type than revolute or fixed, or branches
            into more than one movable chain.
    """
    import xml.etree.ElementTree as ET

    try:
        root = ET.fromstring(urdf)
    except ET.ParseError as exc:
        raise Ur3HanoiError(f"robot URDF is not XML: {exc}") from None
    children: dict[str, list[tuple[str, str, FloatArray, FloatArray | None]]] = {}
    child_links = set()
    links = [link.get("name", "") for link in root.findall("link")]
    for joint in root.findall("joint"):
        kind = joint.get("type")
        parent_el, child_el = joint.find("parent"), joint.find("child")
        if parent_el is None or child_el is None or kind is None:
            raise Ur3HanoiError(f"URDF joint {joint.get('name')!r} lacks a type, parent or child")
        parent_link, child_link = parent_el.get("link", ""), child_el.get("link", "")
        origin = joint.find("origin")
        T = _placement(None if origin is None else origin.get("xyz"), None if origin is None else origin.get("rpy"))
        axis: FloatArray | None = None
        if kind in ("revolute", "continuous"):
            ax = joint.find("axis")
            axis = np.array([float(v) for v in (ax.get("xyz", "1 0 0") if ax is not None else "1 0 0").split()])
            axis = axis / np.linalg.norm(axis)
        elif kind != "fixed":
            raise Ur3HanoiError(f"URDF joint {joint.get('name')!r} is {kind}: only revolute and fixed are supported")
        children.setdefault(parent_link, []).append((joint.get("name", ""), child_link, T, axis))
        child_links.add(child_link)
    roots = [name for name in links if name not in child_links]
    if len(roots) != 1:
        raise Ur3HanoiError(f"URDF has {len(roots)} root links {roots}: expected one")
    names: list[str] = []
    placements: list[FloatArray] = []
    axes: list[FloatArray] = []
    frames: dict[str, tuple[int, FloatArray]] = {}
    stack = [(roots[0], 0, np.eye(4))]
    while stack:
        link, parent_joint, T_joint_link = stack.pop()
        frames[link] = (parent_joint, T_joint_link)
        for name, child, T, axis in children.get(link, []):
            if axis is None:
                stack.append((child, parent_joint, T_joint_link @ T))
                continue
            if parent_joint != len(names):
                raise Ur3HanoiError(f"URDF joint {name!r} starts a second movable chain: expected a serial arm")
            names.append(name)
            placements.append(T_joint_link @ T)
            axes.append(axis)
            stack.append((child, len(names), np.eye(4)))
    # The root link is Pinocchio's universe: a fixed world link moves nothing, so frames stay in the root's frame.
    return UrdfChain(tuple(names), tuple(placements), tuple(axes), frames)


__all__ = ["UrdfChain", "axis_rotation", "parse_chain", "rigid_inverse", "rpy_matrix"]
