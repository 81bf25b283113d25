"""Inverse kinematics of a UR arm: the closed-form branches, and the branch policy tables use.

- :func:`analytic_ik` enumerates the (up to) 8 closed-form solutions of a flange pose from the robot's DH table
  (:mod:`ur3hanoi.robot.registry`); it names each by its configuration branch (shoulder, elbow, wrist signs).
- :func:`solve_on_branch` is what tables use: the closed-form solution on home's branch, measured by FK of the
  URDF model and refined by a numerical solver (:mod:`ur3hanoi.robot.ik_solvers`) only when its residual exceeds
  :data:`~ur3hanoi.robot.ik_solvers.POSITION_TOL` / :data:`~ur3hanoi.robot.ik_solvers.ORIENTATION_TOL` (the
  closed form alone is about 1e-12 m accurate on the UR3, and several times faster); then it requires the home
  branch and the 2pi-equivalent of every joint nearest to home within limits, so moves between waypoints never
  flip the arm. :func:`solve_table_on_branch` does the same for a whole table with one FK pass.

Poses are ``pin.SE3`` or 4x4 matrices. The closed form and its FK check use NumPy only (the DH matrices of
:mod:`ur3hanoi.robot.dh`; the SE(3) products and the URDF chain FK of :mod:`ur3hanoi.robot.chain`, Pinocchio's
numbers): Pinocchio (and placo) are imported only when a pose needs a refinement or an error message names a
pose's roll-pitch-yaw.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import IKError
from ur3hanoi.robot.chain import se3_mul
from ur3hanoi.robot.dh import dh_link
from ur3hanoi.robot.ik_solvers import CLOSED_FORM, IKResult, IKSolver, as_matrix, closest_reach, pose_errors
from ur3hanoi.robot.model import JointLimits, Ur3Model
from ur3hanoi.robot.registry import UR3, DHParameters

if TYPE_CHECKING:
    import pinocchio as pin

Branch = tuple[int, int, int]


def wrap_angle(x: FloatArray | float) -> FloatArray:
    """Angles wrapped to [-pi, pi)."""
    return (np.asarray(x, dtype=float) + math.pi) % (2 * math.pi) - math.pi


# ------------------------------------------------------------------------------------------------ branches


def _p05(q: FloatArray, dh: DHParameters) -> FloatArray:
    """Origin of DH frame 5 (the wrist point used for the shoulder branch) in base [m]."""
    T06 = dh_link(q[0], 0, dh)  # one configuration: six 4x4 products beat the batched dh_fk's set-up
    for i in range(1, 6):
        T06 = T06 @ dh_link(q[i], i, dh)
    return T06[:3, 3] - dh.d[5] * T06[:3, 2]


def branch_of(q: FloatArray, dh: DHParameters = UR3.dh) -> Branch:
    """Configuration branch of ``q`` [rad] as signs (shoulder, elbow, wrist), each +1 or -1.

    shoulder: which of the two base angles that put the wrist point in the arm plane ("left/right");
    elbow: sign of sin(q3) ("up/down"); wrist: sign of sin(q5) ("flip"). ``dh``: the robot's DH table (default
    the UR3's).
    """
    q = np.asarray(q, dtype=float)
    p = _p05(q, dh)
    psi = math.atan2(p[1], p[0])
    shoulder = 1 if float(wrap_angle(q[0] - psi - math.pi / 2)) >= 0.0 else -1
    elbow = 1 if math.sin(q[2]) >= 0.0 else -1
    wrist = 1 if math.sin(q[4]) >= 0.0 else -1
    return (shoulder, elbow, wrist)


BRANCHES: tuple[Branch, ...] = tuple((s, e, w) for s in (1, -1) for e in (1, -1) for w in (1, -1))


def analytic_ik(T_base_tool0: pin.SE3 | FloatArray, only: Branch | None = None,
                dh: DHParameters = UR3.dh) -> dict[Branch, FloatArray]:
    """Closed-form UR IK of a flange (``tool0``) pose in ``base``: ``{branch: q}`` for every reachable branch.

    Angles are in [-pi, pi). Singular wrist configurations (sin q5 ~ 0) are skipped. ``only`` restricts the
    solve to one branch (8x cheaper when the branch is known). ``dh``: the robot's DH table (default the UR3's);
    any UR-geometry table works (d2 = d3 = 0, a1 = a4..a6 = 0, the UR alphas).

    Scalar arithmetic throughout (a table solves one pose at a time, where numpy's per-call cost dominates). With
    the flange axes X, Y, Z and origin p in ``base`` and UR's DH twists (pi/2, 0, 0, pi/2, -pi/2, 0), joints 2-4
    form a planar 3R chain in DH frame 1: ``T14 = inv(A1) T06 inv(A5 A6)`` has origin ``(c1 u_x + s1 u_y,
    u_z - d1)`` with ``u = p + d5 (s6 X + c6 Y) - d6 Z``, and x axis at angle q2 + q3 + q4 with cosine
    ``c1 w_x + s1 w_y`` and sine ``w_z``, ``w = c5 (c6 X - s6 Y) - s5 Z``.
    """
    T = as_matrix(T_base_tool0)
    (xx, yx, zx, px), (xy, yy, zy, py), (xz, yz, zz, pz) = T[:3].tolist()
    D, A = dh.d, dh.a
    d1, d4, d5, d6 = D[0], D[3], D[4], D[5]
    a2, a3 = A[1], A[2]
    wx, wy = px - d6 * zx, py - d6 * zy  # wrist point p05 (its z is not needed)
    r = math.hypot(wx, wy)
    out: dict[Branch, FloatArray] = {}
    if r < abs(d4):
        return out
    psi, phi = math.atan2(wy, wx), math.acos(d4 / r)
    for s1 in (1, -1) if only is None else (only[0],):
        q1 = psi + s1 * phi + math.pi / 2
        c1, sn1 = math.cos(q1), math.sin(q1)
        # z1 = (sin q1, -cos q1, 0): the axis of joints 2-4 in base.
        c5 = (px * sn1 - py * c1 - d4) / d6
        if abs(c5) > 1.0:
            continue
        for s5 in (1, -1) if only is None else (only[2],):
            q5 = s5 * math.acos(c5)
            sin5 = math.sin(q5)
            if abs(sin5) < 1e-10:
                continue
            q6 = math.atan2(-(yx * sn1 - yy * c1) / sin5, (xx * sn1 - xy * c1) / sin5)  # Y.z1, X.z1
            c6, sn6 = math.cos(q6), math.sin(q6)
            ux = px + d5 * (sn6 * xx + c6 * yx) - d6 * zx
            uy = py + d5 * (sn6 * xy + c6 * yy) - d6 * zy
            uz = pz + d5 * (sn6 * xz + c6 * yz) - d6 * zz
            wx5 = c5 * (c6 * xx - sn6 * yx) - sin5 * zx
            wy5 = c5 * (c6 * xy - sn6 * yy) - sin5 * zy
            wz5 = c5 * (c6 * xz - sn6 * yz) - sin5 * zz
            ex, ey = c1 * ux + sn1 * uy, uz - d1  # origin of frame 4 in DH frame 1 (the planar problem)
            c3 = (ex * ex + ey * ey - a2 * a2 - a3 * a3) / (2 * a2 * a3)
            if abs(c3) > 1.0:
                continue
            q234 = math.atan2(wz5, c1 * wx5 + sn1 * wy5)
            for s3 in (1, -1) if only is None else (only[1],):
                q3 = s3 * math.acos(c3)
                q2 = math.atan2(ey, ex) - math.atan2(a3 * math.sin(q3), a2 + a3 * math.cos(q3))
                # By construction the branch is (s1, s3, s5): see branch_of.
                out[(s1, s3, s5)] = wrap_angle(np.array([q1, q2, q3, q234 - q2 - q3, q5, q6]))
    return out


def nearest_equivalent(q: FloatArray, q_ref: FloatArray, limits: JointLimits) -> FloatArray | None:
    """Each joint of ``q`` shifted by a multiple of 2pi to be nearest ``q_ref`` within limits (None if none fits)."""
    out = []
    # Six scalars: plain floats are several times faster than numpy here, and this runs for every table pose.
    for qi, ri, lo, hi in zip(np.asarray(q, dtype=float).tolist(), np.asarray(q_ref, dtype=float).tolist(),
                              limits.q_min, limits.q_max, strict=True):
        x = ri + (qi - ri + math.pi) % (2 * math.pi) - math.pi
        # The nearest equivalent overshoots a limit only when q_ref is within pi of it: take the other turn.
        if x > hi + 1e-12:
            x -= 2 * math.pi
        elif x < lo - 1e-12:
            x += 2 * math.pi
        if not lo - 1e-12 <= x <= hi + 1e-12:
            return None
        out.append(x)
    return np.array(out)


# ------------------------------------------------------------------------------------------ branch policy


def closed_form_result(robot: Ur3Model, T_base_tcp: pin.SE3 | FloatArray, q: FloatArray) -> IKResult:
    """A closed-form solution ``q`` [rad] of ``T_base_tcp`` as an :class:`IKResult`, its errors measured by FK
    of the URDF model (which the DH geometry of :func:`analytic_ik` matches to about 1e-12 m on the UR3): the NumPy
    FK of its chain in ``base`` (:meth:`ur3hanoi.robot.chain.UrdfChain.fk`, Pinocchio's FK to rounding), so a table
    that needs no refinement needs no Pinocchio."""
    dp, dr = pose_errors(robot.chain.fk(q, "tcp"), T_base_tcp)
    return IKResult(q=q, position_error=dp, orientation_error=dr, iterations=0, solver=CLOSED_FORM)


def solve_on_branch(solver: IKSolver, T_base_tcp: pin.SE3 | FloatArray, q_home: FloatArray, label: str = "pose",
                    home_branch: Branch | None = None) -> IKResult:
    """Solve ``T_base_tcp`` on the branch of ``q_home``, each joint the 2pi-equivalent nearest home.

    The closed-form solution on home's branch is taken when FK of the URDF model puts it within
    :data:`POSITION_TOL` and :data:`ORIENTATION_TOL` of the target (the usual case); otherwise (a robot model
    that differs from the DH geometry, a near-singular pose) it seeds ``solver``, which refines it to those
    tolerances without leaving the branch. Either way the result is checked by FK.

    Raises:
        IKError: unreachable pose, no solution on the home branch, out of limits, or not converged; the message
            names ``label``, the target pose and the residual.
    """
    robot = solver.robot
    q_home = np.asarray(q_home, dtype=float)
    if home_branch is None:
        home_branch = branch_of(q_home, robot.dh)
    H_base_tcp = as_matrix(T_base_tcp)
    T_base_tool0 = se3_mul(H_base_tcp, robot.H_tcp_tool0)  # Pinocchio's SE3 product, to the last bit

    def where() -> str:
        import pinocchio as pin

        xyz = np.round(H_base_tcp[:3, 3], 4).tolist()
        rpy = np.round(np.degrees(pin.rpy.matrixToRpy(H_base_tcp[:3, :3])), 2).tolist()
        return f"{label}: target xyz {xyz} m rpy {rpy} deg in base"

    branches = analytic_ik(T_base_tool0, only=home_branch, dh=robot.dh)
    if not branches:
        reachable = sorted(analytic_ik(T_base_tool0, dh=robot.dh))
        if not reachable:
            best = closest_reach(robot, T_base_tcp, q_home)
            raise IKError(f"{where()} is unreachable by the {robot.description.title} (no closed-form solution; "
                          "closest reach leaves a "
                          f"residual of {best.position_error * 1e3:.1f} mm, {math.degrees(best.orientation_error):.1f}"
                          " deg)")
        raise IKError(f"{where()} has no solution on home's branch {home_branch} (reachable: {reachable})")
    q_closed = branches[home_branch]
    seed = nearest_equivalent(q_closed, q_home, robot.limits)
    if seed is None:
        raise IKError(f"{where()}: solution {np.round(np.degrees(q_closed), 3).tolist()} deg is outside the joint "
                      "limits")
    res = closed_form_result(robot, T_base_tcp, seed)
    if res.converged:
        return res
    refined = solver.solve(T_base_tcp, seed)
    q = nearest_equivalent(refined.q, q_home, robot.limits)
    if q is None:
        raise IKError(f"{where()}: solution {np.round(np.degrees(refined.q), 3).tolist()} deg is outside the joint "
                      "limits")
    res = IKResult(q=q, position_error=refined.position_error, orientation_error=refined.orientation_error,
                   iterations=refined.iterations, solver=refined.solver)
    # The refined solution must be the closed-form one it started from (so, on home's branch): a robot model that
    # differs from the DH geometry by micrometres moves it by far less than this bound, while other IK solutions
    # are radians away.
    drift = float(np.max(np.abs(wrap_angle(res.q - seed))))
    if not res.converged or drift > 1e-6:
        raise IKError(
            f"{where()}: {solver.name} did not converge on home's branch {home_branch} "
            f"(residual {res.position_error:.3e} m, {res.orientation_error:.3e} rad, drift {drift:.2e} rad)"
        )
    return res


def solve_table_on_branch(solver: IKSolver, targets: Sequence[pin.SE3 | FloatArray], q_home: FloatArray,
                          labels: Sequence[str], home_branch: Branch | None = None) -> list[IKResult]:
    """:func:`solve_on_branch` of every pose of ``targets`` (``T_base_tcp``), the same results, with the closed
    form's FK check done for all poses in one NumPy pass (a table is 18 poses; most need no refinement). A pose
    without a closed-form solution on home's branch, or whose residual exceeds the tolerances, goes through
    :func:`solve_on_branch` (its refinement, or its error naming ``labels[i]``)."""
    robot = solver.robot
    q_home = np.asarray(q_home, dtype=float)
    if home_branch is None:
        home_branch = branch_of(q_home, robot.dh)
    H = [as_matrix(T) for T in targets]
    seeds: list[FloatArray | None] = []
    for H_base_tcp in H:
        branches = analytic_ik(se3_mul(H_base_tcp, robot.H_tcp_tool0), only=home_branch, dh=robot.dh)
        seeds.append(nearest_equivalent(branches[home_branch], q_home, robot.limits) if branches else None)
    ok = [i for i, q in enumerate(seeds) if q is not None]
    reached = robot.chain.fk(np.array([seeds[i] for i in ok]).reshape(-1, 6), "tcp")
    results: dict[int, IKResult] = {}
    for i, H_reached in zip(ok, reached, strict=True):
        dp, dr = pose_errors(H_reached, H[i])
        res = IKResult(q=seeds[i], position_error=dp, orientation_error=dr, iterations=0,  # type: ignore[arg-type]
                       solver=CLOSED_FORM)
        if res.converged:
            results[i] = res
    return [results[i] if i in results else solve_on_branch(solver, targets[i], q_home, labels[i], home_branch)
            for i in range(len(H))]


__all__ = [
    "BRANCHES",
    "Branch",
    "analytic_ik",
    "branch_of",
    "closed_form_result",
    "nearest_equivalent",
    "solve_on_branch",
    "solve_table_on_branch",
    "wrap_angle",
]
