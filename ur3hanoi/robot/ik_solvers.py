"""IK solvers behind one interface: the result every solve returns, and two numerical refiners.

:class:`PinocchioIK` (damped least squares on the SE(3) log error) and :class:`PlacoIK` (placo's
``KinematicsSolver`` with a frame task) refine a seed to machine precision. Both solve for the ``tcp`` frame in the
controller ``base`` frame and return an :class:`IKResult` whose errors are measured by FK. The closed form and the
branch policy that tables use, seeding these refiners, are :mod:`ur3hanoi.robot.ik`.

Poses are ``pin.SE3`` or 4x4 matrices. Pinocchio (and placo) are imported on a solver's first solve.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.robot.model import Ur3Model

if TYPE_CHECKING:
    import pinocchio as pin

POSITION_TOL = 1e-9  # [m] required accuracy of every table pose
ORIENTATION_TOL = 1e-9  # [rad]
SOLVERS: tuple[str, ...] = ("pinocchio", "placo")
CLOSED_FORM = "closed-form"
"""``IKResult.solver`` of a pose the closed form solved within the tolerances (no refinement)."""


def as_matrix(T: pin.SE3 | FloatArray) -> FloatArray:
    """A pose as a 4x4 homogeneous matrix (a ``pin.SE3`` or a 4x4 array)."""
    return T.homogeneous if hasattr(T, "homogeneous") else np.asarray(T, dtype=float)


def rotation_angle(R: FloatArray) -> float:
    """Angle [rad] of a rotation matrix (the norm of its log), accurate for tiny angles too: ``atan2`` of the
    skew part's norm (the sine, to rounding) and ``(trace - 1) / 2`` (the cosine)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.tolist()
    s = 0.5 * math.sqrt((r21 - r12) ** 2 + (r02 - r20) ** 2 + (r10 - r01) ** 2)
    return math.atan2(s, 0.5 * (r00 + r11 + r22 - 1.0))


def pose_errors(T_actual: pin.SE3 | FloatArray, T_target: pin.SE3 | FloatArray) -> tuple[float, float]:
    """(position error [m], orientation error [rad]) between two poses (``pin.SE3`` or 4x4 matrices)."""
    A, B = as_matrix(T_actual), as_matrix(T_target)
    dp = math.dist(A[:3, 3].tolist(), B[:3, 3].tolist())
    return dp, rotation_angle(A[:3, :3].T @ B[:3, :3])


@dataclass(frozen=True)
class IKResult:
    """Outcome of one IK solve. ``q`` [rad]; errors measured by FK of the ``tcp`` frame (the URDF model's).

    ``solver`` is :data:`CLOSED_FORM` (``iterations`` 0) when the closed form was accurate enough, else the name
    of the numerical solver that refined it.
    """

    q: FloatArray
    position_error: float  # [m]
    orientation_error: float  # [rad]
    iterations: int
    solver: str

    @property
    def converged(self) -> bool:
        return self.position_error <= POSITION_TOL and self.orientation_error <= ORIENTATION_TOL


class IKSolver(Protocol):
    """Numerical IK of the ``tcp`` frame; targets are ``T_base_tcp`` poses in the controller ``base`` frame."""

    name: str
    robot: Ur3Model

    def solve(self, T_base_tcp: pin.SE3 | FloatArray, q_seed: FloatArray) -> IKResult: ...


class PinocchioIK:
    """Damped least squares on the SE(3) log error (full Newton steps with ``Jlog6``).

    Args:
        robot: model with the station's ``tcp`` frame.
        max_iterations: iteration cap (converged solves take 3-6).
        damping: Tikhonov damping of J J^T [-]; tiny so the last steps stay quadratic.
        stop_tol: stop once the log error norm is below this (well under the 1e-9 acceptance).
    """

    name = "pinocchio"

    def __init__(self, robot: Ur3Model, max_iterations: int = 100, damping: float = 1e-12,
                 stop_tol: float = 1e-13) -> None:
        self.robot = robot
        self.max_iterations = max_iterations
        self.damping = damping
        self.stop_tol = stop_tol
        self._damping_eye = damping * np.eye(6)

    def solve(self, T_base_tcp: pin.SE3 | FloatArray, q_seed: FloatArray) -> IKResult:
        import pinocchio as pin

        from ur3hanoi.robot.model import T_BASELINK_BASE

        model, data = self.robot.model, self.robot.data
        fid = self.robot.frame_ids["tcp"]
        # Work in the URDF root frame (base_link) where Pinocchio's oMf lives.
        target = T_BASELINK_BASE * pin.SE3(as_matrix(T_base_tcp))
        q = np.array(q_seed, dtype=float)
        it = 0
        for it in range(1, self.max_iterations + 1):
            pin.forwardKinematics(model, data, q)
            iMd = pin.updateFramePlacement(model, data, fid).actInv(target)
            err = pin.log6(iMd).vector
            if math.sqrt(err @ err) < self.stop_tol:
                break
            J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL)
            J = -pin.Jlog6(iMd.inverse()) @ J
            dq = -J.T @ np.linalg.solve(J @ J.T + self._damping_eye, err)
            # Cap the step: far from the solution a full Gauss-Newton step can leap across branches.
            step = float(np.max(np.abs(dq)))
            if step > 0.5:
                dq *= 0.5 / step
            q = q + dq
        else:
            pin.forwardKinematics(model, data, q)
            iMd = pin.updateFramePlacement(model, data, fid).actInv(target)
        # iMd is the target seen from the reached TCP: its translation norm is the position error.
        dp = float(np.linalg.norm(iMd.translation))
        dr = float(np.linalg.norm(pin.log3(iMd.rotation)))
        return IKResult(q=q, position_error=dp, orientation_error=dr, iterations=it, solver=self.name)


class PlacoIK:
    """placo ``KinematicsSolver`` with one hard-ish frame task on ``tcp`` (floating base masked).

    placo cannot resolve ``package://`` URIs, so it is given the URDF text with absolute mesh paths.
    """

    name = "placo"

    def __init__(self, robot: Ur3Model, max_iterations: int = 50, stop_tol: float = 1e-13) -> None:
        self.robot = robot
        self.max_iterations = max_iterations
        self.stop_tol = stop_tol
        self._built = False  # placo and its model are loaded on the first solve: a table rarely needs any

    def _build(self) -> None:
        import placo  # imported here: placo is heavy and only this solver needs it

        self._names = list(self.robot.model.names[1:])
        self._robot = placo.RobotWrapper("", placo.Flags.ignore_collisions, self.robot.urdf)
        self._solver = placo.KinematicsSolver(self._robot)
        self._solver.mask_fbase(True)
        self._solver.enable_joint_limits(False)  # limits are enforced by solve_on_branch, on the 2pi-shift
        self._solver.enable_velocity_limits(False)
        self._task = self._solver.add_frame_task("tcp", np.eye(4))
        self._task.configure("tcp", "soft", 1.0, 1.0)
        self._built = True

    def solve(self, T_base_tcp: pin.SE3 | FloatArray, q_seed: FloatArray) -> IKResult:
        import pinocchio as pin

        from ur3hanoi.robot.model import T_BASELINK_BASE

        if not self._built:
            self._build()
        T_base_tcp = pin.SE3(as_matrix(T_base_tcp))
        target = (T_BASELINK_BASE * T_base_tcp).homogeneous
        self._task.T_world_frame = target
        for name, v in zip(self._names, np.asarray(q_seed, dtype=float), strict=True):
            self._robot.set_joint(name, float(v))
        self._robot.update_kinematics()
        it = 0
        for it in range(1, self.max_iterations + 1):
            self._solver.solve(True)
            self._robot.update_kinematics()
            T = self._robot.get_T_world_frame("tcp")
            if np.linalg.norm(pin.log6(pin.SE3(T).actInv(pin.SE3(target))).vector) < self.stop_tol:
                break
        q = np.array([self._robot.get_joint(n) for n in self._names])
        dp, dr = pose_errors(self.robot.fk(q, "tcp"), T_base_tcp)
        return IKResult(q=q, position_error=dp, orientation_error=dr, iterations=it, solver=self.name)


def make_solver(name: str, robot: Ur3Model) -> IKSolver:
    """The solver called ``name`` (one of :data:`SOLVERS`) for ``robot``."""
    if name == "pinocchio":
        return PinocchioIK(robot)
    if name == "placo":
        return PlacoIK(robot)
    raise Ur3HanoiError(f"IK solver {name!r} is unknown: expected one of {SOLVERS}")


def closest_reach(robot: Ur3Model, T_base_tcp: pin.SE3 | FloatArray, q_seed: FloatArray) -> IKResult:
    """Heavily damped least squares from ``q_seed``: the pose closest to an unreachable target, for its residual.

    Damping keeps the steps bounded at the workspace boundary, where the Jacobian is singular.
    """
    return PinocchioIK(robot, max_iterations=300, damping=1e-3).solve(T_base_tcp, q_seed)


__all__ = [
    "CLOSED_FORM",
    "ORIENTATION_TOL",
    "POSITION_TOL",
    "SOLVERS",
    "IKResult",
    "IKSolver",
    "PinocchioIK",
    "PlacoIK",
    "as_matrix",
    "closest_reach",
    "make_solver",
    "pose_errors",
    "rotation_angle",
]
