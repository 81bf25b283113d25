"""Forward kinematics of a robot's URDF serial chain in plain NumPy: Pinocchio's ``oMf`` without Pinocchio.

A table of a shipped station needs FK only to measure the closed-form IK's residual (18 poses); importing Pinocchio
for that costs more than the whole rest of ``ur3hanoi tables``. :func:`parse_chain` reads the joints of a URDF (the
same text Pinocchio builds its model from, with the ``tcp`` frame), merges fixed joints into the placements the way
Pinocchio does (a frame's placement in its parent joint's frame), and :meth:`UrdfChain.fk` composes them: the
result equals Pinocchio's ``framesForwardKinematics`` to rounding (tests/robot/test_chain.py compares them on seeded
random configurations). The constant placements (URDF ``rpy`` through urdfdom's quaternion, fixed joints merged) and
the pose products a table's IK reads (:func:`se3_mul`, :func:`se3_act_inv`, :func:`rigid_inverse`,
:func:`rpy_matrix`) follow Pinocchio's order of operations, so they are its numbers bit for bit where its build
fuses no multiply-adds (x86-64): a table and every plan built on it do not change with the path that computed
them. Pinocchio stays the reference model of :class:`ur3hanoi.robot.model.Ur3Model` (Jacobians, collision geometry, the
numerical IK refiners).

Frames: every placement is in the URDF root link's frame (``base_link`` for the UR URDFs, whose ``world`` link is
fixed to it at the identity); FK results are in that frame too, or in the frame a chain is given as its ``base``
(the controller ``base`` of a UR arm, :class:`ur3hanoi.robot.model.Ur3Model`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import Ur3HanoiError


def _quaternion_product(a: tuple[float, float, float, float],
                        b: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    aw, ax, ay, az = a
    bw, bx, by, bz = b
    return (aw * bw - ax * bx - ay * by - az * bz, aw * bx + ax * bw + ay * bz - az * by,
            aw * by + ay * bw + az * bx - ax * bz, aw * bz + az * bw + ax * by - ay * bx)


def _quaternion_matrix(w: float, x: float, y: float, z: float) -> FloatArray:
    """Eigen's ``Quaternion::toRotationMatrix`` of a unit quaternion."""
    tx, ty, tz = 2 * x, 2 * y, 2 * z
    twx, twy, twz = tx * w, ty * w, tz * w
    txx, txy, txz = tx * x, ty * x, tz * x
    tyy, tyz, tzz = ty * y, tz * y, tz * z
    return np.array([[1 - (tyy + tzz), txy - twz, txz + twy],
                     [txy + twz, 1 - (txx + tzz), tyz - twx],
                     [txz - twy, tyz + twx, 1 - (txx + tyy)]])


def rpy_matrix(roll: float, pitch: float, yaw: float) -> FloatArray:
    """Roll-pitch-yaw [rad] (fixed axes x, y, z) as a rotation matrix, ``Rz(yaw) Ry(pitch) Rx(roll)``, computed as
    ``pin.rpy.rpyToMatrix`` does (the product of three axis-angle quaternions), so that it equals it to the last bit
    (tests/robot/test_chain.py)."""
    def half(angle: float, axis: int) -> tuple[float, float, float, float]:
        s, c = math.sin(0.5 * angle), math.cos(0.5 * angle)
        return (c, s if axis == 0 else 0.0, s if axis == 1 else 0.0, s if axis == 2 else 0.0)

    return _quaternion_matrix(*_quaternion_product(_quaternion_product(half(yaw, 2), half(pitch, 1)), half(roll, 0)))


def urdf_rotation(roll: float, pitch: float, yaw: float) -> FloatArray:
    """The rotation a URDF ``rpy`` makes in Pinocchio, to the last bit: urdfdom's quaternion of the half angles
    (normalised), then Eigen's quaternion-to-matrix formula. Equal to :func:`rpy_matrix` to rounding."""
    phi, the, psi = roll / 2.0, pitch / 2.0, yaw / 2.0
    sphi, cphi, sthe, cthe, spsi, cpsi = (math.sin(phi), math.cos(phi), math.sin(the), math.cos(the), math.sin(psi),
                                          math.cos(psi))
    x = sphi * cthe * cpsi - cphi * sthe * spsi
    y = cphi * sthe * cpsi + sphi * cthe * spsi
    z = cphi * cthe * spsi - sphi * sthe * cpsi
    w = cphi * cthe * cpsi + sphi * sthe * spsi
    n = math.sqrt(x * x + y * y + z * z + w * w)
    if n != 0.0:
        x, y, z, w = x / n, y / n, z / n, w / n
    return _quaternion_matrix(w, x, y, z)


def se3_mul(A: FloatArray, B: FloatArray) -> FloatArray:
    """``A B`` of two 4x4 rigid transforms in the order of Eigen's products (``R_A R_B``, ``R_A p_B + p_A``, each sum
    left to right), so that it equals Pinocchio's ``SE3`` product to the last bit."""
    (a00, a01, a02, a03), (a10, a11, a12, a13), (a20, a21, a22, a23) = A[:3].tolist()
    (b00, b01, b02, b03), (b10, b11, b12, b13), (b20, b21, b22, b23) = B[:3].tolist()
    return np.array([
        [a00 * b00 + a01 * b10 + a02 * b20, a00 * b01 + a01 * b11 + a02 * b21, a00 * b02 + a01 * b12 + a02 * b22,
         (a00 * b03 + a01 * b13 + a02 * b23) + a03],
        [a10 * b00 + a11 * b10 + a12 * b20, a10 * b01 + a11 * b11 + a12 * b21, a10 * b02 + a11 * b12 + a12 * b22,
         (a10 * b03 + a11 * b13 + a12 * b23) + a13],
        [a20 * b00 + a21 * b10 + a22 * b20, a20 * b01 + a21 * b11 + a22 * b21, a20 * b02 + a21 * b12 + a22 * b22,
         (a20 * b03 + a21 * b13 + a22 * b23) + a23],
        [0.0, 0.0, 0.0, 1.0]])


def se3_act_inv(A: FloatArray, B: FloatArray) -> FloatArray:
    """``inv(A) B`` as Pinocchio's ``A.actInv(B)`` computes it (``R_A^T R_B``, ``R_A^T (p_B - p_A)``)."""
    At = np.eye(4)
    At[:3, :3] = A[:3, :3].T
    Bs = B.copy()
    Bs[:3, 3] = B[:3, 3] - A[:3, 3]
    return se3_mul(At, Bs)


def rigid_inverse(T: FloatArray) -> FloatArray:
    """Inverse of a 4x4 rigid transform: ``(R^T, -R^T p)``, each sum left to right (Pinocchio's ``SE3.inverse``)."""
    (r00, r01, r02, p0), (r10, r11, r12, p1), (r20, r21, r22, p2) = T[:3].tolist()
    return np.array([[r00, r10, r20, -(r00 * p0 + r10 * p1 + r20 * p2)],
                     [r01, r11, r21, -(r01 * p0 + r11 * p1 + r21 * p2)],
                     [r02, r12, r22, -(r02 * p0 + r12 * p1 + r22 * p2)],
                     [0.0, 0.0, 0.0, 1.0]])


def _placement(xyz: str | None, rpy: str | None) -> FloatArray:
    T = np.eye(4)
    if rpy:
        T[:3, :3] = urdf_rotation(*(float(v) for v in rpy.split()))
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
        H_base_root: the root link's pose in the frame :meth:`fk` reports poses in (4x4); None: the root's own.
    """

    joint_names: tuple[str, ...]
    joint_placements: tuple[FloatArray, ...]
    axes: tuple[FloatArray, ...]
    frames: dict[str, tuple[int, FloatArray]]
    H_base_root: FloatArray | None = None
    _terms: tuple[FloatArray, FloatArray, FloatArray] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        # P Rot(axis, q) = P + sin q (P K) + (1 - cos q) (P K^2) with K the axis's cross-product matrix (Rodrigues):
        # every joint's transform from two scalars, all joints in one NumPy expression.
        P = np.array(self.joint_placements).reshape(-1, 4, 4)
        K = np.zeros((len(self.axes), 4, 4))
        for i, (x, y, z) in enumerate(a.tolist() for a in self.axes):
            K[i, :3, :3] = [[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]]
        object.__setattr__(self, "_terms", (P, P @ K, P @ K @ K))

    def fk(self, q: FloatArray, frame: str) -> FloatArray:
        """4x4 pose of link ``frame`` at joint angles ``q`` [rad], in the root link's frame or, when the chain has
        one, in :attr:`H_base_root`'s base; ``q`` of shape (N, n) gives (N, 4, 4) (one NumPy pass for a whole
        table)."""
        T_root_frame = self._fk_root(q, frame)
        return T_root_frame if self.H_base_root is None else self.H_base_root @ T_root_frame

    def _fk_root(self, q: FloatArray, frame: str) -> FloatArray:
        try:
            parent, placement = self.frames[frame]
        except KeyError:
            raise Ur3HanoiError(f"frame {frame!r} is unknown: expected one of {sorted(self.frames)}") from None
        q = np.asarray(q, dtype=float)
        if parent == 0:
            return np.broadcast_to(placement, (*q.shape[:-1], 4, 4)).copy()
        angles = q[..., :parent]
        P, PK, PK2 = self._terms
        A = P[:parent] + np.sin(angles)[..., None, None] * PK[:parent] + (1.0 - np.cos(angles))[..., None, None] * \
            PK2[:parent]
        T = A[..., 0, :, :]
        for i in range(1, parent):
            T = T @ A[..., i, :, :]
        return T @ placement


def parse_chain(urdf: str, H_base_root: FloatArray | None = None) -> UrdfChain:
    """The serial chain of ``urdf`` (text): its revolute joints from the root link, every link as a frame; FK in the
    root link's frame, or in a base frame in which the root link's pose is ``H_base_root`` (4x4).

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
                stack.append((child, parent_joint, se3_mul(T_joint_link, T)))
                continue
            if parent_joint != len(names):
                raise Ur3HanoiError(f"URDF joint {name!r} starts a second movable chain: expected a serial arm")
            names.append(name)
            placements.append(se3_mul(T_joint_link, T))
            axes.append(axis)
            stack.append((child, len(names), np.eye(4)))
    # The root link is Pinocchio's universe: a fixed world link moves nothing, so frames stay in the root's frame.
    return UrdfChain(tuple(names), tuple(placements), tuple(axes), frames, H_base_root)


__all__ = ["UrdfChain", "axis_rotation", "parse_chain", "rigid_inverse", "rpy_matrix", "se3_act_inv", "se3_mul",
           "urdf_rotation"]
