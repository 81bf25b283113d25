"""A URDF generated from a robot's DH description, for arms without a URDF here (the UR3e).

The frames follow ``ur_description``'s layout exactly (the one example-robot-data's ``ur3_robot.urdf`` uses), so
everything that reads the UR3's URDF reads this one the same way: root ``base_link``; ``base`` = ``base_link``
rotated by pi about z; joints ``shoulder_pan_joint`` .. ``wrist_3_joint`` whose zeros are the DH zeros;
``ee_link`` (x along the tool axis) and ``tool0`` (the DH flange frame) on ``wrist_3_link``. :func:`ur_layout`
gives the joint placements from the DH table (d1, a2, a3, d4, d5, d6 and the two lateral offsets that split d4),
so the FK of this URDF equals the DH FK (checked to 1e-9 m in the tests).

Link shapes are primitive cylinders sized from the DH lengths and ``RobotDescription.link_radius`` (the e-Series
tubes and joint housings, approximately); they are the collision geometry of the planner's clearance checks and
the visual of the MuJoCo model (:mod:`ur3hanoi.sim.dh_model`). Masses and centres of mass are UR's published
dynamics parameters (given in the DH frames; converted to link frames here); inertia tensors, which UR does not
publish, are those of solid cylinders of each link's mass and size.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.registry import RobotDescription

Vec3 = tuple[float, float, float]

LINKS: tuple[str, ...] = ("base_link", "shoulder_link", "upper_arm_link", "forearm_link", "wrist_1_link",
                          "wrist_2_link", "wrist_3_link")
JOINTS: tuple[str, ...] = ("shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
                           "wrist_2_joint", "wrist_3_joint")
_HALF_PI = math.pi / 2


@dataclass(frozen=True)
class JointPlacement:
    """One joint of the UR layout: ``parent`` -> ``child`` at ``xyz`` [m] / URDF ``rpy`` [rad], rotating about
    ``axis`` (child frame)."""

    name: str
    parent: str
    child: str
    xyz: Vec3
    rpy: Vec3
    axis: Vec3


@dataclass(frozen=True)
class Cylinder:
    """A link shape: a cylinder of ``radius`` [m] from ``p0`` to ``p1`` [m, link frame]."""

    link: str
    p0: Vec3
    p1: Vec3
    radius: float

    @property
    def length(self) -> float:
        return float(np.linalg.norm(np.subtract(self.p1, self.p0)))

    @property
    def center(self) -> FloatArray:
        return 0.5 * (np.asarray(self.p0) + np.asarray(self.p1))

    def rotation(self) -> FloatArray:
        """Rotation taking the cylinder's own z axis onto p1 - p0 (link frame)."""
        z = np.subtract(self.p1, self.p0) / self.length
        return np.asarray(pin.Quaternion.FromTwoVectors(np.array([0.0, 0.0, 1.0]), z).matrix())


def ur_layout(r: RobotDescription) -> tuple[JointPlacement, ...]:
    """The six joints of the UR URDF layout for ``r``'s DH table (see the module docstring)."""
    d, a = r.dh.d, r.dh.a
    s, e = r.shoulder_offset, r.elbow_offset
    y, z = (0.0, 1.0, 0.0), (0.0, 0.0, 1.0)
    return (
        JointPlacement(JOINTS[0], LINKS[0], LINKS[1], (0.0, 0.0, d[0]), (0.0, 0.0, 0.0), z),
        JointPlacement(JOINTS[1], LINKS[1], LINKS[2], (0.0, s, 0.0), (0.0, _HALF_PI, 0.0), y),
        JointPlacement(JOINTS[2], LINKS[2], LINKS[3], (0.0, -e, -a[1]), (0.0, 0.0, 0.0), y),
        JointPlacement(JOINTS[3], LINKS[3], LINKS[4], (0.0, 0.0, -a[2]), (0.0, _HALF_PI, 0.0), y),
        JointPlacement(JOINTS[4], LINKS[4], LINKS[5], (0.0, d[3] - s + e, 0.0), (0.0, 0.0, 0.0), z),
        JointPlacement(JOINTS[5], LINKS[5], LINKS[6], (0.0, 0.0, d[4]), (0.0, 0.0, 0.0), y),
    )


def link_shapes(r: RobotDescription) -> tuple[Cylinder, ...]:
    """Cylinders approximating each link (joint housings and tubes), from the DH lengths and link radii."""
    d, a = r.dh.d, r.dh.a
    s, e = r.shoulder_offset, r.elbow_offset
    r0, r1, r2 = r.link_radius
    w2 = d[3] - s + e  # wrist 2 offset along wrist_1_link y
    return (
        Cylinder("base_link", (0.0, 0.0, 0.0), (0.0, 0.0, 0.09), r0),
        Cylinder("shoulder_link", (0.0, 0.0, -0.065), (0.0, 0.0, 0.035), r0),
        Cylinder("shoulder_link", (0.0, 0.0, 0.0), (0.0, s - r0, 0.0), r0 * 0.9),
        Cylinder("upper_arm_link", (0.0, -0.055, 0.0), (0.0, 0.055, 0.0), r0),
        Cylinder("upper_arm_link", (0.0, 0.0, 0.0), (0.0, 0.0, -a[1]), r1),
        Cylinder("upper_arm_link", (0.0, 0.02, -a[1]), (0.0, -e + r1, -a[1]), r1),
        Cylinder("forearm_link", (0.0, -0.045, 0.0), (0.0, 0.045, 0.0), r1),
        Cylinder("forearm_link", (0.0, 0.0, 0.0), (0.0, 0.0, -a[2]), r2),
        Cylinder("wrist_1_link", (0.0, -0.04, 0.0), (0.0, w2 - r2, 0.0), r2),
        Cylinder("wrist_2_link", (0.0, 0.0, -0.04), (0.0, 0.0, d[4] - r2), r2),
        Cylinder("wrist_3_link", (0.0, -0.04, 0.0), (0.0, d[5] - 0.01, 0.0), r2),
    )


def _rpy_matrix(rpy: Vec3) -> FloatArray:
    return np.asarray(pin.rpy.rpyToMatrix(*rpy))


def _dh(theta: float, d: float, a: float, alpha: float) -> FloatArray:
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array([[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0.0, sa, ca, d],
                     [0.0, 0.0, 0.0, 1.0]])


def link_from_dh(r: RobotDescription) -> tuple[FloatArray, ...]:
    """4x4 pose of each moving link's DH frame in its URDF link frame (constant: both are fixed to the link)."""
    T_link = np.eye(4)  # base_link
    T_dh = np.diag([-1.0, -1.0, 1.0, 1.0])  # base in base_link: Rz(pi)
    out = []
    for i, jp in enumerate(ur_layout(r)):
        J = np.eye(4)
        J[:3, :3] = _rpy_matrix(jp.rpy)
        J[:3, 3] = jp.xyz
        T_link = T_link @ J
        T_dh = T_dh @ _dh(0.0, r.dh.d[i], r.dh.a[i], r.dh.alpha[i])
        out.append(np.linalg.inv(T_link) @ T_dh)
    return tuple(out)


@dataclass(frozen=True)
class LinkInertia:
    """Mass [kg], centre of mass [m] and diagonal inertia [kg m^2] about it, in the link frame (axes aligned)."""

    mass: float
    com: Vec3
    diag: Vec3


def link_inertias(r: RobotDescription) -> tuple[LinkInertia, ...]:
    """Per moving link: UR's mass and centre of mass (moved from the DH frame into the link frame) and the inertia
    of a solid cylinder of that mass along the link's longest shape (see the module docstring)."""
    shapes = link_shapes(r)
    out = []
    for i, T in enumerate(link_from_dh(r)):
        com = T[:3, :3] @ np.asarray(r.com_dh[i]) + T[:3, 3]
        mine = [c for c in shapes if c.link == LINKS[i + 1]]
        main = max(mine, key=lambda c: c.length)
        m, rad, length = r.masses[i], main.radius, main.length
        axial = 0.5 * m * rad * rad
        transverse = m * (3 * rad * rad + length * length) / 12.0
        axis = int(np.argmax(np.abs(np.subtract(main.p1, main.p0))))
        diag = [transverse] * 3
        diag[axis] = axial
        out.append(LinkInertia(m, (float(com[0]), float(com[1]), float(com[2])), (diag[0], diag[1], diag[2])))
    return tuple(out)


def _f(x: float) -> str:
    return repr(float(x)) if abs(x) >= 1e-15 else "0.0"


def _v(v: FloatArray | Vec3) -> str:
    return " ".join(_f(float(x)) for x in v)


def urdf_from_dh(r: RobotDescription) -> str:
    """The URDF text of ``r`` in the UR layout (see the module docstring); deterministic."""
    lines = ['<?xml version="1.0"?>', f'<robot name="{r.name}">',
             f"  <!-- Generated by ur3hanoi.robot.urdf from the {r.title} description in ur3hanoi.robot.registry."
             " -->"]
    shapes = link_shapes(r)
    inertias = dict(zip(LINKS[1:], link_inertias(r), strict=True))
    for link in LINKS:
        lines.append(f'  <link name="{link}">')
        for c in (c for c in shapes if c.link == link):
            rpy = pin.rpy.matrixToRpy(c.rotation())
            geom = (f'<origin xyz="{_v(c.center)}" rpy="{_v(rpy)}"/>'
                    f'<geometry><cylinder radius="{_f(c.radius)}" length="{_f(c.length)}"/></geometry>')
            lines.append(f"    <visual>{geom}</visual>")
            lines.append(f"    <collision>{geom}</collision>")
        inertia = inertias.get(link)
        if inertia is not None:
            ix, iy, iz = inertia.diag
            lines.append(f'    <inertial><mass value="{_f(inertia.mass)}"/><origin xyz="{_v(inertia.com)}" '
                         f'rpy="0 0 0"/><inertia ixx="{_f(ix)}" ixy="0" ixz="0" iyy="{_f(iy)}" iyz="0" '
                         f'izz="{_f(iz)}"/></inertial>')
        lines.append("  </link>")
    for i, jp in enumerate(ur_layout(r)):
        lines += [f'  <joint name="{jp.name}" type="revolute">',
                  f'    <parent link="{jp.parent}"/>', f'    <child link="{jp.child}"/>',
                  f'    <origin xyz="{_v(jp.xyz)}" rpy="{_v(jp.rpy)}"/>', f'    <axis xyz="{_v(jp.axis)}"/>',
                  f'    <limit effort="{_f(r.torque[i])}" lower="{_f(-2 * math.pi)}" upper="{_f(2 * math.pi)}" '
                  f'velocity="{_f(r.v_max[i])}"/>',
                  "  </joint>"]
    d6 = r.dh.d[5]
    lines += [
        '  <link name="ee_link"/>',
        '  <joint name="ee_fixed_joint" type="fixed"><parent link="wrist_3_link"/><child link="ee_link"/>'
        f'<origin xyz="0 {_f(d6)} 0" rpy="0 0 {_f(_HALF_PI)}"/></joint>',
        '  <link name="base"/>',
        '  <joint name="base_link-base_fixed_joint" type="fixed"><parent link="base_link"/><child link="base"/>'
        f'<origin xyz="0 0 0" rpy="0 0 {_f(-math.pi)}"/></joint>',
        '  <link name="tool0"/>',
        '  <joint name="wrist_3_link-tool0_fixed_joint" type="fixed"><parent link="wrist_3_link"/>'
        f'<child link="tool0"/><origin xyz="0 {_f(d6)} 0" rpy="{_f(-_HALF_PI)} 0 0"/></joint>',
        "</robot>",
    ]
    return "\n".join(lines) + "\n"


__all__ = ["Cylinder", "JointPlacement", "LinkInertia", "link_from_dh", "link_inertias", "link_shapes",
           "ur_layout", "urdf_from_dh"]
