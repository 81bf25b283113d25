"""The UR3 robot model for MuJoCo, derived from the URDF: ``robots/universal_robots_ur3/ur3.xml`` and ``assets/``.

:func:`derive_ur3_mjcf` turns example-robot-data's ``ur3_robot.urdf`` into ``ur3.xml`` deterministically (12
significant digits); :func:`write_ur3_files` writes it and copies the collision STLs (``python -m ur3hanoi.sim``
runs it; a test checks the committed files are up to date). The changes from the URDF are listed in
``robots/universal_robots_ur3/README.md``. The task scene (:mod:`ur3hanoi.sim.scene`) then edits this model with
:class:`mujoco.MjSpec`.

Why ``ur3.xml`` is written as text and not with :class:`mujoco.MjSpec`: measured with MuJoCo 4.0.0,
``MjSpec.from_file("ur3.xml").to_xml()`` does not give the file back. The 106-line file becomes a 143-line diff:
``to_xml`` writes numbers with 6 significant digits (joint ranges ``-6.28319 6.28319`` instead of
``-6.28318530718 6.28318530718``: the compiled ``jnt_range`` moves by 4.7e-6 rad, ``body_inertia`` by 1.7e-8
kg m^2, ``geom_size`` by 1.5e-8 m), drops every comment and ``autolimits``, expands the ``position`` shortcuts
into ``general`` actuators with raw gain/bias parameters, turns ``fromto`` into pos/quat/size, and adds
``content_type`` and ``size nkey``. ``to_xml`` has no precision option. A model built with MjSpec could therefore
not keep ``ur3.xml`` byte-identical, nor even the same compiled model, and would lose the comments that explain
the collision and suction choices; so the robot file stays string-built here and MjSpec is used where the model is
edited at run time (the task scene).
"""

from __future__ import annotations

import math
import shutil
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.etree import ElementTree

import mujoco
import numpy as np
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.io.resources import robot_dir
from ur3hanoi.robot.model import Q_HOME_LAB, load_ur3
from ur3hanoi.robot.urdf import JOINT_NAMES, ToolOffset, package_dir, urdf_path

ROBOT_DIR = robot_dir()
UR3_XML = ROBOT_DIR / "ur3.xml"
SCENE_XML = ROBOT_DIR / "scene.xml"
SOURCE_PACKAGE = "example-robot-data 4.4.0"

# The lab_sim tool (course URDF: vacuum_gripper = ee_link * xyz (0.059, 0.0535, 0) rpy (0, pi/2, 0)): the default
# suction site of ur3.xml. Task scenes move the site to their own calibration's tool.
DEFAULT_TOOL = ToolOffset(parent="ee_link", xyz=(0.059, 0.0535, 0.0), rpy=(0.0, math.pi / 2, 0.0))


@dataclass(frozen=True)
class JointDrive:
    """Position servo and drive-train parameters of one joint size class.

    Attributes:
        kp: position gain [N m/rad].
        kv: velocity gain [N m s/rad] (the servo damps towards the feed-forward velocity, see
            :func:`ur3hanoi.sim.run_plan`).
        armature: reflected rotor inertia [kg m^2]; a UR3 has ~100:1 harmonic drives, so the rotor dominates the
            light links' inertia and keeps the explicit spring stable at a 2 ms step.
        force_limit: actuator torque limit [N m], UR3 (CB3) datasheet.
    """

    kp: float
    kv: float
    armature: float
    force_limit: float


# Joints 1-3 ("size3": base, shoulder, elbow) and wrists ("size1"). kv is about critical damping for the joint's
# largest effective inertia (kv^2 / 4 kp = 1.25 / 0.072 kg m^2). kp is the servo's holding stiffness: a UR3 holds
# its pose within its +-0.1 mm repeatability (datasheet) because its joint controller has integral action; this PD
# has none, so a load or a contact force deflects it by torque/kp and an error decays with kv/kp. At 2000/500 N m/rad
# (kv/kp = 50 ms) the cup was still 0.02-0.03 mm off the line when the suction switched at a dwell, and, held by
# the grasped block resting under friction, stayed there: 8 blocks on a tall grid (255 moves) drifted the top block
# 4.8 mm (bench/bench_executes.py). Four times that (kv/kp = 25 ms, the same damping ratio; a 3 kg payload at
# 0.5 m still sags 0.9 mm) settles the cup to 0.003 mm within 0.1 s of a dwell's start (the top block then ends
# 1.15 mm off, 2.34 mm with the softer servo and every other correction), and keeps the explicit spring stable at
# the 2 ms step (sqrt(kp / armature) * dt = 0.57 / 0.45 < 2).
DRIVES: dict[str, JointDrive] = {
    "size3": JointDrive(kp=8000.0, kv=200.0, armature=0.1, force_limit=56.0),
    "size1": JointDrive(kp=2000.0, kv=24.0, armature=0.04, force_limit=12.0),
}
# Elbow torque limit is 28 N m (datasheet), the other size3 joints 56 N m: class size3_elbow overrides it.
_ELBOW_FORCE_LIMIT = 28.0  # [N m]
_JOINT_CLASS = {
    "shoulder_pan_joint": "size3",
    "shoulder_lift_joint": "size3",
    "elbow_joint": "size3_elbow",
    "wrist_1_joint": "size1",
    "wrist_2_joint": "size1",
    "wrist_3_joint": "size1",
}


def _g(x: float) -> str:
    """Deterministic short float text (12 significant digits; |x| < 1e-12 written as 0, no negative zero)."""
    s = f"{float(x):.12g}" if abs(x) >= 1e-12 else "0"
    return "0" if s in ("-0", "0") else s


def _range(limit: float) -> str:
    return f"{_g(-limit)} {_g(limit)}"


def _vec(v: Sequence[float] | FloatArray) -> str:
    return " ".join(_g(x) for x in v)


def quat_wxyz(R: FloatArray) -> FloatArray:
    """Rotation matrix -> unit quaternion (w, x, y, z) with w >= 0 (MuJoCo's order; :func:`mujoco.mju_mat2Quat`)."""
    q = np.zeros(4)
    mujoco.mju_mat2Quat(q, np.ascontiguousarray(R, dtype=float).reshape(9))
    return -q if q[0] < 0 else q


def rpy_quat(rpy: Sequence[float]) -> FloatArray:
    """URDF roll-pitch-yaw [rad] (fixed axes x, y, z) -> unit quaternion (w, x, y, z) with w >= 0
    (:func:`mujoco.mju_euler2Quat`, sequence ``XYZ``)."""
    q = np.zeros(4)
    mujoco.mju_euler2Quat(q, np.asarray(rpy, dtype=float), "XYZ")
    return -q if q[0] < 0 else q


def _find(el: ElementTree.Element, path: str) -> ElementTree.Element:
    """The sub-element ``path`` of a URDF element, which the derivation needs."""
    found = el.find(path)
    if found is None:
        raise SimulationError(f"URDF <{el.tag} name={el.get('name')!r}> has no <{path}>: expected a valid URDF")
    return found


def _attr(el: ElementTree.Element, name: str) -> str:
    """The attribute ``name`` of a URDF element, which the derivation needs."""
    value = el.get(name)
    if value is None:
        raise SimulationError(f"URDF <{el.tag}> has no attribute {name!r}: expected a valid URDF")
    return value


def _origin(el: ElementTree.Element | None) -> tuple[list[float], list[float]]:
    if el is None:
        return [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]
    xyz = [float(v) for v in el.get("xyz", "0 0 0").split()]
    rpy = [float(v) for v in el.get("rpy", "0 0 0").split()]
    return xyz, rpy


def _pose_attrs(xyz: Sequence[float], rpy: Sequence[float]) -> str:
    out = ""
    if any(abs(v) > 0 for v in xyz):
        out += f' pos="{_vec(xyz)}"'
    if any(abs(v) > 0 for v in rpy):
        out += f' quat="{_vec(rpy_quat(rpy))}"'
    return out


def cup_geometry(T_ee_tcp: pin.SE3) -> dict[str, str]:
    """Visual suction cup in ``ee_link`` coordinates: a bracket from the flange and a cup ending at the TCP.

    Returns MJCF attribute strings (``fromto`` [m], 12 significant digits) for the ``suction_bracket``
    (key ``"bracket"``) and ``suction_cup`` (key ``"cup"``) geoms.
    """
    p = T_ee_tcp.translation
    z = T_ee_tcp.rotation[:, 2]
    cup_top = p - 0.02 * z  # the cup is 20 mm long, its lip at the suction point
    start = np.array([0.006, 0.0, 0.0])  # just beyond the flange face (ee_link x = tool axis)
    return {"bracket": _vec([*start, *cup_top]), "cup": _vec([*cup_top, *(p - 0.002 * z)])}


def T_ee_tcp(tool: ToolOffset) -> pin.SE3:
    """TCP pose in ``ee_link`` for any tool parent (``tool0`` offsets are converted through the URDF)."""
    return load_ur3(tool).T_flange_tcp("ee_link")


def _inertial(link: ElementTree.Element, pad: str) -> list[str]:
    """The ``<inertial>`` line of a URDF link with mass (none for a frame-only link)."""
    inertial = link.find("inertial")
    mass = float(_attr(_find(inertial, "mass"), "value")) if inertial is not None else 0.0
    if inertial is None or mass <= 0:
        return []
    xyz, rpy = _origin(inertial.find("origin"))
    inertia = _find(inertial, "inertia").attrib
    full = [float(inertia[k]) for k in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz")]
    inert = f'diaginertia="{_vec(full[:3])}"' if not any(full[3:]) else f'fullinertia="{_vec(full)}"'
    return [f'{pad}<inertial pos="{_vec(xyz)}"{_pose_attrs([0.0, 0.0, 0.0], rpy)} mass="{_g(mass)}" {inert}/>']


def _joint(joint: ElementTree.Element, pad: str) -> str:
    """The ``<joint>`` line of a revolute URDF joint, in its drive class with the URDF's axis and range."""
    axis = [float(v) for v in _attr(_find(joint, "axis"), "xyz").split()]
    lim = _find(joint, "limit")
    lo, hi = float(_attr(lim, "lower")), float(_attr(lim, "upper"))
    name = _attr(joint, "name")
    return (f'{pad}<joint name="{name}" class="{_JOINT_CLASS[name].split("_")[0]}" axis="{_vec(axis)}" '
            f'range="{_g(lo)} {_g(hi)}"/>')


def _suction_cup(pad: str) -> list[str]:
    """The ``suction_cup`` body of ``ee_link``: the cup's bracket and cylinder, and the ``suction`` site at the
    default tool's TCP."""
    T = T_ee_tcp(DEFAULT_TOOL)
    cup = cup_geometry(T)
    return [
        f'{pad}<body name="suction_cup">',
        f'{pad}  <geom name="suction_bracket" class="suction" type="capsule" size="0.006" fromto="{cup["bracket"]}"/>',
        f'{pad}  <geom name="suction_cup" class="suction" type="cylinder" size="0.009" fromto="{cup["cup"]}"/>',
        f'{pad}  <site name="suction" pos="{_vec(T.translation)}" quat="{_vec(quat_wxyz(T.rotation))}"/>',
        f"{pad}</body>",
    ]


@dataclass(frozen=True)
class _UrdfTree:
    """A URDF's links by name and each link's child joints; :meth:`body` writes a link's ``<body>`` subtree."""

    links: dict[str | None, ElementTree.Element]
    children: dict[str, list[ElementTree.Element]]

    @classmethod
    def parse(cls, path: Path) -> _UrdfTree:
        root = ElementTree.parse(path).getroot()
        children: dict[str, list[ElementTree.Element]] = {}
        for j in root.findall("joint"):
            children.setdefault(_attr(_find(j, "parent"), "link"), []).append(j)
        return cls({lk.get("name"): lk for lk in root.findall("link")}, children)

    def body(self, name: str, depth: int, joint: ElementTree.Element | None, meshes: list[str]) -> list[str]:
        """The ``<body>`` lines of link ``name`` reached through ``joint`` (None: the root), indented ``depth``
        levels, and of its descendants; appends the collision meshes used to ``meshes``."""
        pad = "  " * depth
        link = self.links[name]
        attrs = f'name="{name}"' + ("" if joint is None else _pose_attrs(*_origin(joint.find("origin"))))
        moving = joint is not None and joint.get("type") == "revolute"
        if name == "base_link":
            attrs += ' childclass="ur3"'
        elif moving:
            attrs += ' gravcomp="1"'  # stands in for the UR controller's own model-based gravity compensation
        lines = [f"{pad}<body {attrs}>", *_inertial(link, pad + "  ")]
        if joint is not None and moving:
            lines.append(_joint(joint, pad + "  "))
        for col in link.findall("collision"):
            mesh = col.find("geometry/mesh")
            if mesh is None:
                continue  # ee_link's 1 cm box: replaced by the suction cup below
            meshes.append(Path(mesh.get("filename", "")).stem)
            lines.append(f'{pad}  <geom name="{name}_mesh" mesh="{meshes[-1]}"'
                         f'{_pose_attrs(*_origin(col.find("origin")))}/>')
        if name == "ee_link":
            lines += _suction_cup(pad + "  ")
        for j in self.children.get(name, []):
            lines += self.body(_attr(_find(j, "child"), "link"), depth + 1, j, meshes)
        if len(lines) == 1:  # a frame-only link (base, tool0): self-closing
            return [lines[0].removesuffix(">") + "/>"]
        return [*lines, f"{pad}</body>"]


def _defaults() -> list[str]:
    """The ``<default>`` section: link geoms and sites, the drive classes (:data:`DRIVES`), the suction cup's."""
    d3, d1 = DRIVES["size3"], DRIVES["size1"]
    return [
        "  <default>",
        '    <default class="ur3">',
        "      <!-- contype 2 / conaffinity 1: the links hit the table and blocks (contype 1) but not each other:",
        "           MuJoCo collides the STL meshes' convex hulls, and those of the upper arm and wrist 1 overlap in",
        "           reachable poses (a false self-collision). -->",
        '      <geom type="mesh" contype="2" conaffinity="1" rgba="0.7 0.7 0.7 1" group="2"/>',
        '      <site size="0.004" rgba="1 0 0 1" group="4"/>',
        '      <default class="size3">',
        f'        <joint armature="{_g(d3.armature)}"/>',
        f'        <position kp="{_g(d3.kp)}" kv="{_g(d3.kv)}" forcerange="{_range(d3.force_limit)}"/>',
        '        <default class="size3_elbow">',
        f'          <position forcerange="{_range(_ELBOW_FORCE_LIMIT)}"/>',
        "        </default>",
        "      </default>",
        '      <default class="size1">',
        f'        <joint armature="{_g(d1.armature)}"/>',
        f'        <position kp="{_g(d1.kp)}" kv="{_g(d1.kv)}" forcerange="{_range(d1.force_limit)}"/>',
        "      </default>",
        "      <!-- The suction cup never collides: suction is a weld equality, and at contact the suction point of",
        "           the lab's calibrations is inside the block (contact_depth below its top face). -->",
        '      <default class="suction">',
        '        <geom type="cylinder" contype="0" conaffinity="0" mass="0" rgba="0.15 0.15 0.15 1" group="2"/>',
        "      </default>",
        "    </default>",
        "  </default>",
    ]


def derive_ur3_mjcf(urdf: Path | None = None) -> str:
    """The text of ``robots/universal_robots_ur3/ur3.xml``, derived deterministically from ``ur3_robot.urdf``.

    Changes from the URDF (see ``robots/universal_robots_ur3/README.md``): visual ``.dae`` meshes dropped and the
    collision STLs used as visuals too; ``ee_link``'s 1 cm collision box replaced by a non-colliding suction cup
    body with the ``suction`` site (lab_sim tool by default); the ``world`` link dropped (``base_link`` is the root
    body); armature, position actuators with datasheet torque limits, gravity compensation on the moving links, the
    ``base_link``/``shoulder_link`` contact excluded, a ``home`` keyframe.
    """
    meshes: list[str] = []
    body = _UrdfTree.parse(urdf if urdf is not None else urdf_path()).body("base_link", 2, None, meshes)
    home = _vec(Q_HOME_LAB)
    text = [
        '<mujoco model="ur3">',
        f"  <!-- Generated by `python -m ur3hanoi.sim` from {SOURCE_PACKAGE} ur_description/urdf/ur3_robot.urdf.",
        "       Do not edit by hand: change ur3hanoi.sim.derive_ur3_mjcf and rerun the script. -->",
        '  <compiler angle="radian" meshdir="assets" autolimits="true"/>',
        '  <option integrator="implicitfast" timestep="0.002"/>',
        *_defaults(),
        "",
        "  <asset>",
        *(f'    <mesh name="{m}" file="{m}.stl"/>' for m in meshes),
        "  </asset>",
        "",
        "  <worldbody>",
        *body,
        "  </worldbody>",
        "",
        "  <contact>",
        "    <!-- The static base mesh overlaps the shoulder mesh and would lock the pan joint. -->",
        '    <exclude body1="base_link" body2="shoulder_link"/>',
        "  </contact>",
        "",
        "  <actuator>",
        *(f'    <position name="{j.removesuffix("_joint")}" joint="{j}" class="{_JOINT_CLASS[j]}"/>'
          for j in JOINT_NAMES),
        "  </actuator>",
        "",
        "  <keyframe>",
        "    <!-- The lab's home: radians([120, -90, 90, -90, -90, 0]). -->",
        f'    <key name="home" qpos="{home}" ctrl="{home}"/>',
        "  </keyframe>",
        "</mujoco>",
    ]
    return "\n".join(text) + "\n"


def ur3_mesh_sources(urdf: Path | None = None) -> list[Path]:
    """The collision STL files ``ur3.xml`` uses, in the installed example-robot-data."""
    root = ElementTree.parse(urdf if urdf is not None else urdf_path()).getroot()
    share = package_dir()
    return [share / mesh.get("filename", "").removeprefix("package://")
            for mesh in root.findall("link/collision/geometry/mesh")]


def write_ur3_files(out_dir: Path = ROBOT_DIR) -> list[Path]:
    """Regenerate ``ur3.xml`` and copy the STL meshes into ``assets/`` (what ``python -m ur3hanoi.sim`` runs).

    Returns the written files: the meshes, then ``ur3.xml``.
    """
    assets = out_dir / "assets"
    assets.mkdir(parents=True, exist_ok=True)
    written = []
    for src in ur3_mesh_sources():
        dst = assets / src.name
        shutil.copyfile(src, dst)
        written.append(dst)
    xml = out_dir / "ur3.xml"
    xml.write_text(derive_ur3_mjcf())
    written.append(xml)
    return written
