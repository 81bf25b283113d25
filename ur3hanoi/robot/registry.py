"""The robots ur3hanoi knows: one frozen :class:`RobotDescription` per arm, looked up by name.

This module is the one home of each robot's numbers: its DH table (link lengths and twists) is written here and
nowhere else in the package; the URDF check, the DH matrices (:mod:`ur3hanoi.robot.dh`), the closed-form IK, the
generated URDF and the MuJoCo model all read it (tests/robot/test_registry.py greps the source for a second copy).

A calibration names its robot (``robot.model: ur3e``; ``ur3`` when absent) and everything robot-specific is read
from its description: the DH table (kinematics, closed-form IK), the datasheet limits, where its URDF and MuJoCo
model come from, and the published dynamics of arms that have no URDF here. Nothing else in the package branches
on a robot's name.

Sources:

- ``ur3`` (CB3): DH, speed limits and torques from Universal Robots' published DH table and the UR3 datasheet;
  URDF and meshes from example-robot-data's ``ur3_robot.urdf``; MuJoCo model ``robots/universal_robots_ur3``.
- ``ur3e`` (e-Series): DH from Universal Robots' published table ("DH parameters for calculations of kinematics
  and dynamics", the same numbers as ``../shared/lab/ros2-interface.md``), link masses and centres of mass (in the
  DH link frames) from the same page; speeds 180 / 360 deg/s and the 56 / 28 / 12 N m joint torques (size 2 base
  and shoulder, size 1 elbow, size 0 wrists) from the UR3e datasheet. There is no UR3e URDF in example-robot-data:
  its URDF and MuJoCo model are generated from this description with primitive shapes (:mod:`ur3hanoi.robot.urdf`,
  :mod:`ur3hanoi.sim.dh_model`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

Vec3 = tuple[float, float, float]
N_JOINTS = 6
"""Joints of every registered arm (6R)."""


@dataclass(frozen=True)
class DHParameters:
    """Standard DH table of a 6R UR arm [m, rad]: joint i's transform is Rz(q_i) Tz(d_i) Tx(a_i) Rx(alpha_i)."""

    d: tuple[float, float, float, float, float, float]
    a: tuple[float, float, float, float, float, float]
    alpha: tuple[float, float, float, float, float, float]


_UR_ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)


@dataclass(frozen=True)
class RobotDescription:
    """One robot arm (see the module docstring for the sources of each value).

    Attributes:
        name: registry key, as written in calibrations (``ur3``, ``ur3e``).
        title: for people ("UR3 (CB3)").
        dh: the DH table.
        v_max: joint speed limits [rad/s] (datasheet).
        a_max, j_max: acceleration [rad/s^2] and jerk [rad/s^3] limits used by the planner (not published by UR).
        torque: joint torque limits [N m] (datasheet), the MuJoCo actuators' force range.
        model_source: ``"urdf"``: example-robot-data's URDF file ``urdf_file`` and the MJCF folder ``mjcf_dir``
            derived from it; ``"dh"``: URDF and MJCF generated from this description.
        urdf_file: URDF file name under example-robot-data's ``ur_description/urdf`` (``model_source == "urdf"``).
        mjcf_dir: folder under ``ur3hanoi/robot/models`` (Menagerie naming ``<maker>_<model>``).
        masses: link masses [kg], shoulder .. wrist 3 (``model_source == "dh"``).
        com_dh: centre of mass of each link in its DH frame [m] (``model_source == "dh"``).
        shoulder_offset, elbow_offset: lateral offsets [m] of the upper arm and forearm from the joint-1 axis in
            the UR URDF layout (``d4 = shoulder_offset - elbow_offset + wrist-2 offset``); they place the link
            shapes, not the kinematics.
        link_radius: radius [m] of the link shapes of a generated model: base/shoulder, upper arm/forearm, wrists.
        control_rate_hz: the controller's servo rate [Hz]: 125 on CB3, 500 on e-Series (the official drivers'
            ``loop_hz`` / ``update_rate``; URCL ``rtde_client.h``).
        course_suction_io: the course's suction wiring on this arm: (digital output switching the cup, digital
            input of the vacuum switch, analog input of the vacuum sensor), as ``set_io`` / ``io_states`` pins.
            UR3 (ECE 470): the course's ``ur3_driver.cpp`` maps ``io_0`` to ``set_digital_out(0, ...)``: digital
            output 0; the lab manual's feedback on Digital Input 0 and Analog Input 0.
            UR3e: UMD ENME480's bridge switches digital output 1 and reads digital input 0, analog input 0.
        course_vacuum_generator: the ``set_io`` pin of the output that switches the cell's vacuum generator, on for
            the whole session, or None (UR3: the cup's output is all there is). UR3e: ENME480's bridge
            (``ur3e_mrc_enme480_ctrl.cpp``) switches pin 12 (configurable output 4) on at start, off on exit.
    """

    name: str
    title: str
    dh: DHParameters
    v_max: tuple[float, ...]
    a_max: tuple[float, ...]
    j_max: tuple[float, ...]
    torque: tuple[float, ...]
    model_source: Literal["urdf", "dh"]
    mjcf_dir: str
    urdf_file: str = ""
    masses: tuple[float, ...] = ()
    com_dh: tuple[Vec3, ...] = ()
    shoulder_offset: float = 0.1198
    elbow_offset: float = 0.0925
    link_radius: tuple[float, float, float] = (0.045, 0.035, 0.03)
    control_rate_hz: float = 125.0
    course_suction_io: tuple[int, int, int] = (0, 0, 0)
    course_vacuum_generator: int | None = None


_SPEED = (math.pi,) * 3 + (2 * math.pi,) * 3  # 180 deg/s joints 1-3, 360 deg/s wrists (both datasheets)
_ACC = (4.0,) * 3 + (8.0,) * 3
CB3_CONTROL_RATE_HZ = 125.0
E_SERIES_CONTROL_RATE_HZ = 500.0
"""[Hz] The controllers' servo rates (see :attr:`RobotDescription.control_rate_hz`)."""
CB3_CONTROL_PERIOD_S = 1.0 / CB3_CONTROL_RATE_HZ
"""[s] The CB3 controller's servo cycle (8 ms)."""
# [rad/s^3] Each acceleration cap reached within one CB3 servo cycle: 500 / 1000 rad/s^3. UR publishes no jerk
# limit; the source and what it costs the carried block are written at ur3hanoi.robot.model.DEFAULT_JERK_MAX. The UR3e
# keeps the same value: the simulated suction hold that grounds it was measured up to 2000 rad/s^3 on the UR3.
_JERK = tuple(a / CB3_CONTROL_PERIOD_S for a in _ACC)

UR3 = RobotDescription(
    name="ur3", title="UR3 (CB3)",
    dh=DHParameters(d=(0.1519, 0.0, 0.0, 0.11235, 0.08535, 0.0819), a=(0.0, -0.24365, -0.21325, 0.0, 0.0, 0.0),
                    alpha=_UR_ALPHA),
    v_max=_SPEED, a_max=_ACC, j_max=_JERK, torque=(56.0, 56.0, 28.0, 12.0, 12.0, 12.0),
    model_source="urdf", urdf_file="ur3_robot.urdf", mjcf_dir="universal_robots_ur3",
    control_rate_hz=CB3_CONTROL_RATE_HZ, course_suction_io=(0, 0, 0),
)

UR3E = RobotDescription(
    name="ur3e", title="UR3e (e-Series)",
    dh=DHParameters(d=(0.15185, 0.0, 0.0, 0.13105, 0.08535, 0.0921), a=(0.0, -0.24355, -0.2132, 0.0, 0.0, 0.0),
                    alpha=_UR_ALPHA),
    v_max=_SPEED, a_max=_ACC, j_max=_JERK, torque=(56.0, 56.0, 28.0, 12.0, 12.0, 12.0),
    model_source="dh", mjcf_dir="universal_robots_ur3e",
    masses=(1.98, 3.4445, 1.437, 0.871, 0.805, 0.261),
    com_dh=((0.0, -0.02, 0.0), (0.13, 0.0, 0.1157), (0.05, 0.0, 0.0238), (0.0, 0.0, 0.01), (0.0, 0.0, 0.01),
            (0.0, 0.0, -0.02)),
    shoulder_offset=0.12, elbow_offset=0.093, link_radius=(0.046, 0.035, 0.0315),
    control_rate_hz=E_SERIES_CONTROL_RATE_HZ, course_suction_io=(1, 0, 0),
    course_vacuum_generator=12,
)

ROBOTS: dict[str, RobotDescription] = {r.name: r for r in (UR3, UR3E)}
"""Every known robot by name."""
DEFAULT_ROBOT = UR3


def robot_description(name: str) -> RobotDescription:
    """The robot called ``name``; ``KeyError`` lists the known ones."""
    try:
        return ROBOTS[name]
    except KeyError:
        raise KeyError(f"robot {name!r} is unknown: expected one of {', '.join(ROBOTS)}") from None


def check_description(r: RobotDescription) -> list[str]:
    """What is wrong with a description (empty when it is usable): six joints everywhere, positive limits, the UR
    wrist geometry the closed-form IK needs (alpha = pi/2, 0, 0, pi/2, -pi/2, 0; a1 = a4 = a5 = a6 = 0,
    d2 = d3 = 0), and dynamics for generated models."""
    out = []
    for field in ("v_max", "a_max", "j_max", "torque"):
        values = getattr(r, field)
        if len(values) != N_JOINTS or not all(math.isfinite(v) and v > 0 for v in values):
            out.append(f"{r.name}.{field} = {values}: expected {N_JOINTS} finite values > 0")
    d = r.dh
    if any(abs(x - y) > 1e-15 for x, y in zip(d.alpha, _UR_ALPHA, strict=True)):
        out.append(f"{r.name}.dh.alpha = {d.alpha}: expected the UR wrist (pi/2, 0, 0, pi/2, -pi/2, 0)")
    if any(d.a[i] != 0.0 for i in (0, 3, 4, 5)) or d.d[1] != 0.0 or d.d[2] != 0.0 or not d.a[1] < 0 or not d.a[2] < 0:
        out.append(f"{r.name}.dh: a1 = a4 = a5 = a6 = 0, d2 = d3 = 0 and a2, a3 < 0 expected (UR geometry)")
    if not all(x > 0 for x in (d.d[0], d.d[3], d.d[4], d.d[5])):
        out.append(f"{r.name}.dh: d1, d4, d5, d6 > 0 expected")
    if r.model_source == "urdf" and not r.urdf_file:
        out.append(f"{r.name}: model_source 'urdf' needs urdf_file")
    if r.model_source == "dh" and (len(r.masses) != N_JOINTS or len(r.com_dh) != N_JOINTS
                                   or not all(m > 0 for m in r.masses)):
        out.append(f"{r.name}: model_source 'dh' needs {N_JOINTS} masses > 0 and centres of mass")
    return out


__all__ = [
    "DEFAULT_ROBOT",
    "ROBOTS",
    "UR3",
    "UR3E",
    "DHParameters",
    "RobotDescription",
    "check_description",
    "robot_description",
]
