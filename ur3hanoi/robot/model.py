"""The UR3 (CB3) model and the other registered arms: frames, datasheet limits, and forward kinematics.

Frames (all right-handed, metres):

- ``base``: the UR controller's base frame, the frame of the DH convention. **Every joint value and every
  ``T_base_*`` pose in ur3hanoi is in this frame**, like the lab's tables and the teach pendant.
- ``base_link``: the URDF root. It is ``base`` rotated by pi about z (``T_baselink_base = Rz(pi)``).
- ``tool0``: the flange, z along the tool axis (the DH end frame).
- ``ee_link``: the flange with x along the tool axis (the course's suction offset is given from it).
- ``tcp``: the suction point, added to the model from a :class:`ToolOffset`.

Joint values follow the controller convention: the URDF's joint zeros equal the DH zeros, so the same ``q`` [rad]
drives both; only the root frame differs.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cache, cached_property
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot.chain import UrdfChain, parse_chain, rigid_inverse, se3_act_inv
from ur3hanoi.robot.registry import CB3_CONTROL_PERIOD_S, N_JOINTS, UR3, DHParameters, RobotDescription
from ur3hanoi.robot.urdf import FLANGE_FRAMES, JOINT_NAMES, ToolOffset, urdf_text

if TYPE_CHECKING:
    import pinocchio as pin

    T_BASELINK_BASE: pin.SE3

# Controller `base` seen from URDF `base_link`: a half turn about z (as a 4x4 matrix; T_BASELINK_BASE is the same
# as a pin.SE3, made on first use so that importing this module does not import Pinocchio).
H_BASELINK_BASE: FloatArray = np.eye(4)
H_BASELINK_BASE[:2, :2] = [[math.cos(math.pi), -math.sin(math.pi)], [math.sin(math.pi), math.cos(math.pi)]]
H_BASE_BASELINK: FloatArray = rigid_inverse(H_BASELINK_BASE)


@cache
def _se3(name: str) -> pin.SE3:
    import pinocchio as pin

    T = pin.SE3(pin.utils.rotate("z", math.pi), np.zeros(3))
    return T if name == "T_BASELINK_BASE" else T.inverse()


def __getattr__(name: str) -> object:
    """``T_BASELINK_BASE``: :data:`H_BASELINK_BASE` as a ``pin.SE3`` (Pinocchio imported on first use)."""
    if name == "T_BASELINK_BASE":
        return _se3(name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

# The lab's home: radians([120, -90, 90, -90, -90, 0]).
Q_HOME_LAB: tuple[float, ...] = tuple(math.radians(d) for d in (120.0, -90.0, 90.0, -90.0, -90.0, 0.0))


# [rad/s^2] Acceleration caps (joints 1-3, wrists): not published by UR; the lab's values (see JointLimits.a_max).
DEFAULT_ACCEL_MAX: tuple[float, ...] = UR3.a_max
# [s] The CB3 controller's servo cycle (125 Hz).
CONTROL_PERIOD_S = CB3_CONTROL_PERIOD_S
# [rad/s^3] Jerk limits: each acceleration cap reached within one servo cycle, a_max / 8 ms = 500 rad/s^3 (joints
# 1-3) and 1000 rad/s^3 (wrists). Source: UR publishes no jerk limit and the controller's movej steps its
# acceleration, which at 125 Hz is exactly such a one-cycle ramp: a planner with a lower jerk is slower than the
# program it replaces for no physical reason (20/40 rad/s^3 made the plan 4 % slower than the lab program). What
# this costs the carried block is measured by bench/bench_suction_hold.py (bench/REPORT.md): in MuJoCo the suction
# weld (0.004 s) stretches at most 0.056 mm on lab_sim and 0.078 mm on lab_real at 100-2000 rad/s^3, against the
# 10 mm at which the seal counts as broken (SuctionConfig.hold_tolerance): a margin above 100.
DEFAULT_JERK_MAX: tuple[float, ...] = UR3.j_max  # = a_max / CONTROL_PERIOD_S (the registry's UR3 entry)


@dataclass(frozen=True)
class JointLimits:
    """UR3 joint limits, from the CB3 datasheet unless stated.

    The URDF of example-robot-data carries UR5-like velocity/effort values: they are deliberately not used.

    Attributes:
        q_min, q_max: position limits [rad]; datasheet +-2pi on every joint. ROS configs often restrict the elbow
            to +-pi: pass ``elbow_limit=math.pi`` to :meth:`ur3`.
        v_max: speed limits [rad/s]; datasheet 180 deg/s for base/shoulder/elbow, 360 deg/s for the wrists.
        a_max: acceleration limits [rad/s^2]. Not published by UR; default 4 rad/s^2 (joints 1-3) and 8 rad/s^2
            (wrists) keeps the UR3's 56/28/12 N m torques with margin at the lab's 0.0225 kg payload.
        j_max: jerk limits [rad/s^3]. Not published by UR: default :data:`DEFAULT_JERK_MAX`, see there.
    """

    q_min: tuple[float, ...]
    q_max: tuple[float, ...]
    v_max: tuple[float, ...]
    a_max: tuple[float, ...]
    j_max: tuple[float, ...]

    @classmethod
    def for_robot(cls, robot: RobotDescription, elbow_limit: float = 2 * math.pi) -> JointLimits:
        """``robot``'s limits (:mod:`ur3hanoi.robot.registry`): +-2pi on every joint (``elbow_limit`` [rad] on the
        elbow), its datasheet speeds and the planner's accelerations and jerks."""
        base = cls.ur3(elbow_limit)
        return cls(q_min=base.q_min, q_max=base.q_max, v_max=robot.v_max, a_max=robot.a_max, j_max=robot.j_max)

    @classmethod
    def ur3(cls, elbow_limit: float = 2 * math.pi) -> JointLimits:
        """Datasheet limits; ``elbow_limit`` [rad] optionally restricts the elbow (ROS configs use pi)."""
        if not 0.0 < elbow_limit <= 2 * math.pi:
            raise Ur3HanoiError(f"elbow_limit = {elbow_limit!r} rad is invalid: expected 0 < elbow_limit <= 2*pi")
        two_pi = 2 * math.pi
        q_max = (two_pi, two_pi, elbow_limit, two_pi, two_pi, two_pi)
        return cls(
            q_min=tuple(-x for x in q_max),
            q_max=q_max,
            v_max=(math.pi,) * 3 + (two_pi,) * 3,
            a_max=DEFAULT_ACCEL_MAX,
            j_max=DEFAULT_JERK_MAX,
        )

    def within_position(self, q: FloatArray, tol: float = 1e-12) -> bool:
        """True when every joint of ``q`` [rad] is inside [q_min, q_max] (with ``tol`` [rad] slack)."""
        q = np.asarray(q, dtype=float)
        return bool(np.all(q >= np.asarray(self.q_min) - tol) and np.all(q <= np.asarray(self.q_max) + tol))


def _link_lengths(chain: UrdfChain) -> dict[str, float]:
    def p(name: str) -> FloatArray:
        return chain.joint_placements[chain.joint_names.index(name)][:3, 3]

    return {
        "d1": float(p("shoulder_pan_joint")[2]),
        "a2": float(p("elbow_joint")[2]),
        "a3": float(p("wrist_1_joint")[2]),
        "d4": float(p("shoulder_lift_joint")[1] + p("elbow_joint")[1] + p("wrist_2_joint")[1]),
        "d5": float(p("wrist_3_joint")[2]),
        "d6": float(chain.frames["tool0"][1][1, 3]),
    }


class Ur3Model:
    """The UR3 with an optional ``tcp`` frame: NumPy FK of its URDF chain (:mod:`ur3hanoi.robot.chain`) and the
    Pinocchio model (built on first use of :attr:`model`, :attr:`data`, :attr:`frame_ids`, :meth:`fk`).

    FK results are expressed in the controller ``base`` frame (see the module docstring).

    Args:
        tool: the suction point offset; without it the ``tcp`` frame equals ``tool0``.
        limits: joint limits to report and enforce (datasheet values by default).
    """

    def __init__(self, tool: ToolOffset | None = None, limits: JointLimits | None = None,
                 robot: RobotDescription = UR3) -> None:
        self.tool = tool if tool is not None else ToolOffset(parent="tool0")
        self.limits = limits if limits is not None else JointLimits.for_robot(robot)
        self.description = robot
        self.dh: DHParameters = robot.dh
        self.urdf = urdf_text(self.tool, absolute_meshes=True, robot=robot)
        self.chain = parse_chain(self.urdf, H_BASE_BASELINK)
        if self.chain.joint_names != JOINT_NAMES:
            raise Ur3HanoiError(f"URDF joints {self.chain.joint_names} are not the UR3's {JOINT_NAMES}")
        lengths = _link_lengths(self.chain)
        d, a = robot.dh.d, robot.dh.a
        # The URDF must encode the registry's DH lengths: a UR5's URDF (d1 = 0.089159 m) fails here.
        expected_lengths = {"d1": d[0], "a2": -a[1], "a3": -a[2], "d4": d[3], "d5": d[4], "d6": d[5]}
        for key, expected in expected_lengths.items():
            if abs(lengths[key] - expected) > 1e-6:
                raise Ur3HanoiError(
                    f"{robot.urdf_file or robot.name}: link length {key} = {lengths[key]} m, expected the "
                    f"{robot.title}'s {expected} m (is this a UR5/UR10 URDF?)"
                )
        for name in ("base", "base_link", "tool0", "tcp", "ee_link"):
            if name not in self.chain.frames:
                raise Ur3HanoiError(f"{robot.urdf_file or robot.name}: the URDF has no {name!r} link")
        # The flange seen from the TCP: constant, used by every IK solve to turn a TCP target into a flange one.
        f = self.chain.frames
        if f["tcp"][0] != f["tool0"][0]:
            raise Ur3HanoiError(f"{robot.urdf_file or robot.name}: the tcp and tool0 links are not fixed to the same "
                                "joint")
        self.H_tcp_tool0: FloatArray = rigid_inverse(se3_act_inv(f["tool0"][1], f["tcp"][1]))

    @cached_property
    def model(self) -> pin.Model:
        """Pinocchio's model of the URDF (with the ``tcp`` frame), built on first use."""
        import pinocchio as pin

        model = pin.buildModelFromXML(self.urdf)
        if tuple(model.names[1:]) != JOINT_NAMES:
            raise Ur3HanoiError(f"URDF joints {tuple(model.names[1:])} are not the UR3's {JOINT_NAMES}")
        return model

    @cached_property
    def data(self) -> pin.Data:
        """Pinocchio's data of :attr:`model` (one per model: :meth:`fk` is not thread-safe)."""
        return self.model.createData()

    @cached_property
    def frame_ids(self) -> dict[str, int]:
        """Pinocchio frame ids of ``base``, ``base_link``, ``tool0``, ``tcp`` and ``ee_link``."""
        return {name: self.model.getFrameId(name) for name in ("base", "base_link", "tool0", "tcp", "ee_link")}

    @cached_property
    def T_tcp_tool0(self) -> pin.SE3:
        """:attr:`H_tcp_tool0` as a ``pin.SE3``."""
        import pinocchio as pin

        return pin.SE3(self.H_tcp_tool0)

    @property
    def nq(self) -> int:
        return N_JOINTS

    def fk(self, q: FloatArray, frame: str = "tcp") -> pin.SE3:
        """Pose of ``frame`` in the controller ``base`` frame at joint angles ``q`` [rad] (Pinocchio's FK)."""
        import pinocchio as pin

        try:
            fid = self.frame_ids[frame]
        except KeyError:
            raise Ur3HanoiError(f"frame {frame!r} is unknown: expected one of {sorted(self.frame_ids)}") from None
        pin.framesForwardKinematics(self.model, self.data, np.asarray(q, dtype=float))
        return _se3("T_BASE_BASELINK") * self.data.oMf[fid]

    def fk_matrix(self, q: FloatArray, frame: str = "tcp") -> FloatArray:
        """4x4 pose of ``frame`` in the controller ``base`` frame at ``q`` [rad] ((N, 4, 4) for ``q`` of shape
        (N, 6)): the NumPy FK of the URDF chain (:attr:`chain`, whose base is the controller's), equal to :meth:`fk`
        to rounding (no Pinocchio)."""
        if frame not in ("base", "base_link", "tool0", "tcp", "ee_link"):
            raise Ur3HanoiError(f"frame {frame!r} is unknown: expected one of "
                                f"{sorted(('base', 'base_link', 'tool0', 'tcp', 'ee_link'))}")
        return self.chain.fk(q, frame)

    def frame_jacobian_local(self, q: FloatArray, frame: str = "tcp") -> FloatArray:
        """6x6 Jacobian of ``frame`` in its own (LOCAL) frame; frame-independent of the root rotation."""
        import pinocchio as pin

        return pin.computeFrameJacobian(
            self.model, self.data, np.asarray(q, dtype=float), self.frame_ids[frame], pin.LOCAL
        )

    def H_flange_tcp(self, flange: str = "tool0") -> FloatArray:
        """:meth:`T_flange_tcp` as a 4x4 matrix, from the URDF chain (no Pinocchio)."""
        if flange not in FLANGE_FRAMES:
            raise Ur3HanoiError(f"flange frame {flange!r} is invalid: expected one of {FLANGE_FRAMES}")
        f = self.chain.frames
        return se3_act_inv(f[flange][1], f["tcp"][1])

    def T_flange_tcp(self, flange: str = "tool0") -> pin.SE3:
        """The constant TCP pose in a flange frame (``tool0`` or ``ee_link``)."""
        f = self.model.frames
        return f[self.frame_ids[flange]].placement.actInv(f[self.frame_ids["tcp"]].placement)


@cache
def load_ur3(tool: ToolOffset | None = None, limits: JointLimits | None = None,
             robot: RobotDescription = UR3) -> Ur3Model:
    """Cached :class:`Ur3Model` for a tool offset (models are read-only after construction); ``robot`` picks
    another arm of :mod:`ur3hanoi.robot.registry` (the UR3 by default).

    Not thread-safe: each model owns one ``pin.Data`` used by :meth:`Ur3Model.fk`.
    """
    return Ur3Model(tool, limits, robot)


__all__ = [
    "H_BASELINK_BASE",
    "H_BASE_BASELINK",
    "Q_HOME_LAB",
    "T_BASELINK_BASE",
    "JointLimits",
    "Ur3Model",
    "load_ur3",
]
