"""MuJoCo models of robots described by DH only (the UR3e), built with :class:`mujoco.MjSpec`.

:func:`build_dh_robot_spec` builds the same body tree, names and drives as ``robots/universal_robots_ur3/ur3.xml``
(bodies ``base_link`` .. ``wrist_3_link``, ``ee_link`` with the ``suction_cup`` body and ``suction`` site,
``tool0``; joints ``shoulder_pan_joint`` ..; position actuators ``shoulder_pan`` ..; the ``floor`` plane and a
light as in ``scene.xml``), so the task scene (:mod:`ur3hanoi.sim.scene`) edits either model the same way. Link
placements are the UR URDF layout of the robot's DH table (:func:`ur3hanoi.robot.urdf.ur_layout` and
:func:`~ur3hanoi.robot.urdf.fixed_frames`, which the generated URDF uses too); the visual and collision shapes are
the primitive cylinders of :func:`ur3hanoi.robot.urdf.link_shapes` (in the e-Series' blue and grey, so it is never
mistaken for the UR3's meshes), and the masses, centres of mass and inertias are
:func:`ur3hanoi.robot.urdf.link_inertias` (UR's published dynamics parameters). Drives: the UR3 model's gains and
armature (:data:`ur3hanoi.sim.model.DRIVES`) with the robot's datasheet torque limits.

:func:`write_dh_robot_files` writes the model as ``<robot>.xml`` into its folder under ``ur3hanoi/robot/models`` (for
viewing with ``python -m mujoco.viewer``); the simulator always builds it from the description.
"""

from __future__ import annotations

import math
from pathlib import Path

import mujoco
import numpy as np

from ur3hanoi.robot.model import Q_HOME_LAB
from ur3hanoi.robot.registry import RobotDescription
from ur3hanoi.robot.urdf import JOINT_NAMES, LINKS, fixed_frames, link_inertias, link_shapes, ur_layout
from ur3hanoi.sim.model import DEFAULT_TOOL, DRIVES, T_ee_tcp, cup_geometry, quat_wxyz, rpy_quat

_LINK_RGBA = {  # e-Series: blue joint caps, grey tubes
    "base_link": (0.35, 0.55, 0.8, 1.0), "shoulder_link": (0.35, 0.55, 0.8, 1.0),
    "upper_arm_link": (0.75, 0.77, 0.8, 1.0), "forearm_link": (0.75, 0.77, 0.8, 1.0),
    "wrist_1_link": (0.35, 0.55, 0.8, 1.0), "wrist_2_link": (0.35, 0.55, 0.8, 1.0),
    "wrist_3_link": (0.35, 0.55, 0.8, 1.0),
}
_BASE_INERTIA = (2.0, (0.0, 0.0, 0.045), (0.0042, 0.0042, 0.0021))  # static base: mass [kg], com [m], diag


def _floats(text: str) -> list[float]:
    return [float(v) for v in text.split()]


def build_dh_robot_spec(robot: RobotDescription) -> mujoco.MjSpec:
    """The robot and a floor/light scene as an :class:`mujoco.MjSpec` (see the module docstring)."""
    spec = mujoco.MjSpec()
    spec.modelname = f"{robot.name} scene"
    spec.compiler.autolimits = True
    spec.compiler.degree = False  # ranges in radians
    spec.option.timestep = 0.002
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 1280, 720
    spec.worldbody.add_light(pos=[0, 0, 1.5], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL)
    spec.worldbody.add_geom(name="floor", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                            rgba=[0.2, 0.3, 0.4, 1.0])

    shapes = link_shapes(robot)
    inertias = link_inertias(robot)

    def add_shapes(body: mujoco.MjsBody, link: str) -> None:
        for i, c in enumerate(s for s in shapes if s.link == link):
            body.add_geom(name=f"{link}_shape{i}", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                          fromto=[*c.p0, *c.p1], size=[c.radius, 0, 0], contype=2, conaffinity=1, group=2,
                          rgba=list(_LINK_RGBA[link]), mass=0.0)

    base = spec.worldbody.add_body(name="base_link")
    m, com, diag = _BASE_INERTIA
    base.explicitinertial = True
    base.mass, base.ipos, base.inertia = m, list(com), list(diag)
    add_shapes(base, "base_link")
    parent = base
    for i, jp in enumerate(ur_layout(robot)):
        body = parent.add_body(name=jp.child, pos=list(jp.xyz),
                               quat=list(rpy_quat(jp.rpy)), gravcomp=1.0)
        inertia = inertias[i]
        body.explicitinertial = True
        body.mass, body.ipos, body.inertia = inertia.mass, list(inertia.com), list(inertia.diag)
        drive = DRIVES["size3" if i < 3 else "size1"]
        body.add_joint(name=jp.name, type=mujoco.mjtJoint.mjJNT_HINGE, axis=list(jp.axis),
                       range=[-2 * math.pi, 2 * math.pi], armature=drive.armature)
        add_shapes(body, jp.child)
        act = spec.add_actuator(name=jp.name.removesuffix("_joint"), target=jp.name,
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=drive.kp, kv=drive.kv)
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-robot.torque[i], robot.torque[i]]
        parent = body

    fixed = {f.child: f for f in fixed_frames(robot)}
    ee = parent.add_body(name="ee_link", pos=list(fixed["ee_link"].xyz), quat=list(rpy_quat(fixed["ee_link"].rpy)))
    T = T_ee_tcp(DEFAULT_TOOL)
    cup = cup_geometry(T)
    cup_body = ee.add_body(name="suction_cup")
    for name, kind, size, fromto in (("suction_bracket", mujoco.mjtGeom.mjGEOM_CAPSULE, 0.006, cup["bracket"]),
                                     ("suction_cup", mujoco.mjtGeom.mjGEOM_CYLINDER, 0.009, cup["cup"])):
        cup_body.add_geom(name=name, type=kind, size=[size, 0, 0], fromto=_floats(fromto), contype=0,
                          conaffinity=0, mass=0.0, rgba=[0.15, 0.15, 0.15, 1.0], group=2)
    cup_body.add_site(name="suction", pos=list(T.translation), quat=list(quat_wxyz(T.rotation)), size=[0.004, 0, 0],
                      rgba=[1, 0, 0, 1], group=4)
    parent.add_body(name="tool0", pos=list(fixed["tool0"].xyz), quat=list(rpy_quat(fixed["tool0"].rpy)))
    spec.add_exclude(bodyname1=LINKS[0], bodyname2=LINKS[1])
    spec.add_key(name="home", qpos=list(Q_HOME_LAB), ctrl=list(Q_HOME_LAB))
    assert tuple(j.name for j in spec.joints) == JOINT_NAMES
    return spec


def robot_dir_for(robot: RobotDescription) -> Path:
    """The robot's folder under ``ur3hanoi/robot/models``."""
    from ur3hanoi.io.resources import robots_dir

    return robots_dir() / robot.mjcf_dir


def write_dh_robot_files(robot: RobotDescription, out_dir: Path | None = None) -> Path:
    """Write ``<robot>.xml`` (MuJoCo's own XML of :func:`build_dh_robot_spec`) into ``out_dir`` (default the robot's
    folder); returns the file."""
    folder = out_dir if out_dir is not None else robot_dir_for(robot)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{robot.name}.xml"
    spec = build_dh_robot_spec(robot)
    spec.compile()
    path.write_text(spec.to_xml())
    return path


def compiled_masses(robot: RobotDescription) -> np.ndarray:
    """Body masses [kg] of the compiled model, base_link .. wrist_3_link (for checks and reports)."""
    model = build_dh_robot_spec(robot).compile()
    return np.array([model.body(name).mass[0] for name in LINKS])
