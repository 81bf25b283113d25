"""Why a pose is off: a typo in one joint, two entries swapped, an entry copied or recorded in the wrong slot.

- **One joint** (:func:`joint_typo`): for each joint ``j`` the recorded pose is turned about that joint's axis by
  the angle that brings the suction point (and the tool orientation) closest to the target; with the joint's axis
  ``u`` and the TCP's lever ``r`` (perpendicular to ``u``) from the Jacobian at the recorded pose, the best angle
  for the position is the signed angle from ``r`` to the target's lever about ``u``, for the orientation the
  rotation error's component along ``u``; their weighted mean (weights: the lever in mm per rad over the position
  threshold, 57.3 deg per rad over the orientation threshold) is tried too. FK of each candidate decides; the
  joint whose change leaves the smallest normalized error explains the deviation if that error is within the
  thresholds.
- **Swapped** (:func:`find_swaps`): two entries whose measured points each lie within the threshold of the other's
  grid point: swapped heights (same tower), swapped towers (same height), or on/above swapped.
- **Wrong slot** (:func:`nearest_slot`): the grid slot nearest to a measured point, when it is not its own.
- **Copied** (:func:`duplicates`): bit-identical joint values in two different slots.

Joints are numbered 1..6 for people (``JOINT_LABELS``), angles shown in degrees next to radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.ik import wrap_angle
from ur3hanoi.robot.model import Ur3Model
from ur3hanoi.station.grid import R_world_tcp_down
from ur3hanoi.tables import Slot

JOINT_LABELS: tuple[str, ...] = ("base", "shoulder", "elbow", "wrist 1", "wrist 2", "wrist 3")
"""What the teach pendant calls joints 1..6."""

MIN_TYPO_DEG = 0.5
"""[deg] a single-joint change smaller than this is noise, not a typo."""
MIN_SIGN_DEG = 10.0
"""[deg] a joint value at least this far from 0 and 180 deg, negated, is called a sign typo."""


def angle_text(rad: float) -> str:
    """``"-45.0 deg (-0.785 rad)"``: degrees as on the pendant, radians as in the table."""
    return f"{math.degrees(rad):.1f} deg ({rad:.3f} rad)"


@dataclass(frozen=True)
class JointTypo:
    """The single-joint change that best explains a pose's deviation.

    Attributes:
        joint: 0-based joint index (people read ``joint + 1``).
        recorded: the recorded joint value [rad].
        predicted: the value that puts the pose on the grid [rad].
        residual_mm, residual_deg: what is left of the deviation after the change [mm], [deg].
        explains: whether the change explains the deviation (residual within the thresholds).
    """

    joint: int
    recorded: float
    predicted: float
    residual_mm: float
    residual_deg: float
    explains: bool

    @property
    def sign(self) -> bool:
        """True when the value that fits is the recorded one negated (a minus sign typed or lost), whole turns
        aside, within 1 deg, and negating it changes it by at least twice :data:`MIN_SIGN_DEG` (a value near 0 or
        180 deg negated is as much an ordinary typo)."""
        change = abs(float(wrap_angle(2.0 * self.recorded)))
        return change >= math.radians(2.0 * MIN_SIGN_DEG) and abs(float(wrap_angle(
            self.recorded + self.predicted))) < math.radians(1.0)

    def describe(self) -> str:
        """``"a typo in joint 2 (shoulder): recorded -45.0 deg (-0.785 rad), the grid predicts -55.0 deg ..."``
        (``"a sign typo in joint 2 ..."`` when :attr:`sign`)."""
        kind = "a sign typo" if self.sign else "a typo"
        predicted = -self.recorded if self.sign else self.predicted
        return (f"{kind} in joint {self.joint + 1} ({JOINT_LABELS[self.joint]}): recorded {angle_text(self.recorded)}, "
                f"the grid predicts {angle_text(predicted)}")


def _errors(robot: Ur3Model, T_wb: pin.SE3, q: FloatArray, target: pin.SE3) -> tuple[float, float]:
    T = T_wb * robot.fk(q, "tcp")
    dp = float(np.linalg.norm(T.translation - target.translation)) * 1e3
    dr = math.degrees(float(np.linalg.norm(pin.log3(target.rotation.T @ T.rotation))))
    return dp, dr


def _best_single_joint(robot: Ur3Model, T_world_base: pin.SE3, q0: FloatArray, p_target: FloatArray,
                       rot_world: FloatArray, scale_mm: float, scale_deg: float,
                       errors: Callable[[FloatArray], tuple[float, float]]) -> tuple[int, float, float, float] | None:
    """The single-joint change (joint, delta [rad], error [mm], error [deg]) of ``q0`` with the least weighed
    ``errors``; None when no change of at least :data:`MIN_TYPO_DEG` is a candidate.

    Per joint, three candidates: the turn that best undoes the world rotation ``rot_world`` (its component along the
    joint's axis), the turn that carries the TCP round the axis towards ``p_target`` [m, world], and their blend
    weighed by the lever arm, because a typo moves both position and orientation and either may dominate."""
    T = T_world_base * robot.fk(q0, "tcp")
    R = T.rotation
    J = robot.frame_jacobian_local(q0, "tcp")
    best: tuple[float, int, float, float, float] | None = None
    for j in range(len(q0)):
        u = R @ J[3:, j]
        v = R @ J[:3, j]
        lever = np.cross(v, u)  # TCP minus its foot on joint j's axis, perpendicular to the axis
        radius = float(np.linalg.norm(lever))
        d = p_target - (T.translation - lever)
        d_perp = d - u * float(u @ d)
        candidates = [float(u @ rot_world)]
        if radius > 1e-6 and float(np.linalg.norm(d_perp)) > 1e-9:
            d_pos = math.atan2(float(u @ np.cross(lever, d_perp)), float(lever @ d_perp))
            a_p, a_r = (radius * 1e3 / scale_mm) ** 2, (180.0 / math.pi / scale_deg) ** 2
            candidates += [d_pos, (a_p * d_pos + a_r * candidates[0]) / (a_p + a_r)]
        for delta in candidates:
            if abs(math.degrees(delta)) < MIN_TYPO_DEG:
                continue
            qj = q0.copy()
            qj[j] += delta
            dp, dr = errors(qj)
            cost = (dp / scale_mm) ** 2 + (dr / scale_deg) ** 2
            if best is None or cost < best[0]:
                best = (cost, j, float(delta), dp, dr)
    return None if best is None else best[1:]


def joint_typo(robot: Ur3Model, T_world_base: pin.SE3, q: Sequence[float], p_target: FloatArray, yaw: float,
               tol_mm: float, tol_deg: float) -> JointTypo | None:
    """The single-joint change of ``q`` [rad] that best moves the TCP to ``p_target`` [m, world], pointing down at
    ``yaw`` [rad] (see the module docstring); None when no joint change of at least :data:`MIN_TYPO_DEG` helps."""
    q0 = np.asarray(q, dtype=float)
    target = pin.SE3(R_world_tcp_down(yaw), np.asarray(p_target, dtype=float))
    T = T_world_base * robot.fk(q0, "tcp")
    R = T.rotation
    rot_err = pin.log3(target.rotation @ R.T)  # world-frame rotation that would align the tool
    best = _best_single_joint(robot, T_world_base, q0, target.translation, rot_err, tol_mm, tol_deg,
                              lambda qj: _errors(robot, T_world_base, qj, target))
    if best is None:
        return None
    j, delta, dp, dr = best
    return JointTypo(joint=j, recorded=float(q0[j]), predicted=float(q0[j] + delta), residual_mm=dp, residual_deg=dr,
                     explains=dp <= tol_mm and dr <= tol_deg)


def nearest_slot(p_world: FloatArray, grid_points: dict[Slot, FloatArray]) -> tuple[Slot, float]:
    """The slot whose grid point is nearest ``p_world`` [m], and that distance [mm]."""
    slot = min(grid_points, key=lambda s: float(np.linalg.norm(grid_points[s] - p_world)))
    return slot, float(np.linalg.norm(grid_points[slot] - p_world)) * 1e3


def find_swaps(slots: Sequence[Slot], p_world: FloatArray, grid_points: dict[Slot, FloatArray],
               suspects: Sequence[int], tol_mm: float) -> dict[int, tuple[int, float, float]]:
    """Pairs of points that fit the grid when their slots are exchanged, for the points in ``suspects``.

    Returns:
        ``{i: (j, mm_i, mm_j)}``: point ``i`` measured at slot ``slots[j]`` is ``mm_i`` from it and point ``j`` at
        ``slots[i]`` is ``mm_j`` from it [mm], both within ``tol_mm``; the closest partner per suspect.
    """
    out: dict[int, tuple[int, float, float]] = {}
    for i in suspects:
        best: tuple[float, int, float, float] | None = None
        for j, slot_j in enumerate(slots):
            if j == i or slot_j == slots[i]:
                continue
            d_i = float(np.linalg.norm(p_world[i] - grid_points[slot_j])) * 1e3
            d_j = float(np.linalg.norm(p_world[j] - grid_points[slots[i]])) * 1e3
            if d_i <= tol_mm and d_j <= tol_mm and (best is None or d_i + d_j < best[0]):
                best = (d_i + d_j, j, d_i, d_j)
        if best is not None:
            out[i] = (best[1], best[2], best[3])
    return out


def swap_kind(a: Slot, b: Slot) -> str:
    """``"swapped heights"``, ``"swapped towers"``, ``"on and above swapped"`` or ``"swapped entries"``."""
    if a[0] == b[0] and a[1] == b[1]:
        return "on and above swapped"
    if a[0] == b[0] and a[2] == b[2]:
        return "swapped heights"
    if a[1] == b[1] and a[2] == b[2]:
        return "swapped towers"
    return "swapped entries"


def duplicates(slots: Sequence[Slot], qs: Sequence[Sequence[float]], shared: Sequence[bool]) -> dict[int, int]:
    """``{i: j}``: point ``i`` holds exactly the joint values of point ``j`` (the first such, ``j != i``) recorded
    for another slot; points in ``shared`` (one "above" pose shared by a tower's heights) are not compared."""
    out: dict[int, int] = {}
    keys = [tuple(float(v) for v in q) for q in qs]
    for i in range(len(slots)):
        if shared[i]:
            continue
        for j in range(len(slots)):
            if j != i and not shared[j] and slots[j] != slots[i] and keys[j] == keys[i]:
                out[i] = j
                break
    return out


def diagnose(robot: Ur3Model, T_world_base: pin.SE3, slots: Sequence[Slot], qs: Sequence[Sequence[float]],
             p_world: FloatArray, rot_deg: FloatArray, targets: FloatArray, grid_points: dict[Slot, FloatArray],
             suspects: Sequence[int], yaw: float, tol_mm: float, tol_deg: float, labels: Sequence[str]
             ) -> dict[int, str]:
    """What probably happened to each suspect: copied, swapped, recorded in the wrong slot, a typo in one joint.

    A pose recorded in the wrong slot keeps the grid's tool orientation; when both a wrong slot and a typo in one
    joint explain a deviation, the one leaving the smaller normalized error is given.

    Args:
        robot, T_world_base: the robot model and its base pose in world.
        slots, qs, p_world: every gridded point's slot, joint values [rad] and measured suction point [m, world].
        rot_deg: each point's orientation error from the grid pose [deg].
        targets: each point's grid suction point [m, world], shape (N, 3).
        grid_points: the grid's suction point of every slot.
        suspects: indices of the points to explain.
        yaw: the grid's tool yaw [rad]; tol_mm, tol_deg: the thresholds.
        labels: how each point is named (``"tower 1 height 2 on (real_pos[0][1][0])"``).
    """
    from ur3hanoi.station.grid import pose_label

    dup = duplicates(slots, qs, [False] * len(slots))
    swaps = find_swaps(slots, p_world, grid_points, suspects, tol_mm)
    out: dict[int, str] = {}
    for i in suspects:
        if i in dup:
            out[i] = f"identical to {labels[dup[i]]}: a copied entry"
        elif i in swaps:
            j, di, dj = swaps[i]
            out[i] = (f"{swap_kind(slots[i], slots[j])} with {labels[j]}: exchanged, both are within "
                      f"{max(di, dj):.1f} mm of the grid")
        else:
            slot, d = nearest_slot(p_world[i], grid_points)
            typo = joint_typo(robot, T_world_base, qs[i], targets[i], yaw, tol_mm, tol_deg)
            misplaced = slot != slots[i] and d <= tol_mm and rot_deg[i] <= tol_deg
            cost_slot = (d / tol_mm) ** 2 + (rot_deg[i] / tol_deg) ** 2
            typo_fits = typo is not None and typo.explains
            cost_typo = (typo.residual_mm / tol_mm) ** 2 + (typo.residual_deg / tol_deg) ** 2 if typo else math.inf
            if misplaced and not (typo_fits and cost_typo < cost_slot):
                out[i] = f"it fits {pose_label(*slot)} ({d:.1f} mm): recorded in the wrong slot?"
            elif typo is not None and typo_fits:
                out[i] = f"likely {typo.describe()}"
            else:
                out[i] = "not explained by a typo in one joint: re-record it"
    return out


# ------------------------------------------------------------------------------- heading-free (check-table --fit)


def _tilt_after(robot: Ur3Model, T_world_base: pin.SE3, q: FloatArray, p_target: FloatArray, axis: FloatArray
                ) -> tuple[float, float]:
    T = T_world_base * robot.fk(q, "tcp")
    dp = float(np.linalg.norm(T.translation - p_target)) * 1e3
    dt = math.degrees(math.acos(float(np.clip(T.rotation[:, 2] @ axis, -1.0, 1.0))))
    return dp, dt


def joint_typo_point(robot: Ur3Model, T_world_base: pin.SE3, q: Sequence[float], p_target: FloatArray,
                     axis: FloatArray, scale_mm: float, scale_deg: float) -> JointTypo | None:
    """The single-joint change of ``q`` [rad] that best moves the suction point to ``p_target`` [m, world] and the
    suction axis onto ``axis`` (unit vector, world), the heading about the axis left free; None when no change of
    at least :data:`MIN_TYPO_DEG` helps. ``explains`` is left False: the caller decides (see
    :func:`diagnose_contacts`). Errors are weighed by ``scale_mm`` and ``scale_deg``."""
    q0 = np.asarray(q, dtype=float)
    p_target = np.asarray(p_target, dtype=float)
    T = T_world_base * robot.fk(q0, "tcp")
    R = T.rotation
    z = R[:, 2]
    w = np.cross(z, axis)
    s = float(np.linalg.norm(w))
    turn = w / s * math.atan2(s, float(z @ axis)) if s > 1e-12 else np.zeros(3)  # world rotation: z onto axis
    best = _best_single_joint(robot, T_world_base, q0, p_target, turn, scale_mm, scale_deg,
                              lambda qj: _tilt_after(robot, T_world_base, qj, p_target, axis))
    if best is None:
        return None
    j, delta, dp, dt = best
    return JointTypo(joint=j, recorded=float(q0[j]), predicted=float(q0[j] + delta), residual_mm=dp, residual_deg=dt,
                     explains=False)


def joint_typo_level(robot: Ur3Model, T_world_base: pin.SE3, q: Sequence[float], z_level: float, axis: FloatArray,
                     scale_mm: float, scale_deg: float) -> JointTypo | None:
    """:func:`joint_typo_point` for a tower's only contact, whose place nothing else gives: the single-joint change
    of ``q`` [rad] that best brings the suction point to the height ``z_level`` [m, world] and the suction axis onto
    ``axis``; its residual in mm is the height's alone."""
    q0 = np.asarray(q, dtype=float)
    T = T_world_base * robot.fk(q0, "tcp")
    z = T.rotation[:, 2]
    w = np.cross(z, axis)
    s = float(np.linalg.norm(w))
    turn = w / s * math.atan2(s, float(z @ axis)) if s > 1e-12 else np.zeros(3)
    target = np.array([T.translation[0], T.translation[1], z_level])

    def errors(qj: FloatArray) -> tuple[float, float]:
        Tj = T_world_base * robot.fk(qj, "tcp")
        dt = math.degrees(math.acos(float(np.clip(Tj.rotation[:, 2] @ axis, -1.0, 1.0))))
        return abs(float(Tj.translation[2]) - z_level) * 1e3, dt

    best = _best_single_joint(robot, T_world_base, q0, target, turn, scale_mm, scale_deg, errors)
    if best is None:
        return None
    j, delta, dp, dt = best
    return JointTypo(joint=j, recorded=float(q0[j]), predicted=float(q0[j] + delta), residual_mm=dp, residual_deg=dt,
                     explains=False)


TYPO_SHARE = 0.25
"""A single-joint change is called a likely typo only when it leaves at most this share of the deviation (and at
most the never-flagged distance and tilt): one joint explains most of a large error."""


def diagnose_contacts(robot: Ur3Model, T_world_base: pin.SE3, slots: Sequence[Slot], qs: Sequence[Sequence[float]],
                      p_world: FloatArray, tilt_deg: FloatArray, targets: FloatArray,
                      grid_points: dict[Slot, FloatArray], suspects: Sequence[int], axis: FloatArray,
                      flag_mm: float, flag_deg: float, ok_mm: float, ok_deg: float, labels: Sequence[str]
                      ) -> dict[int, str]:
    """What probably happened to each flagged contact, the heading about the suction axis left free: a copied
    entry, two swapped entries, a pose recorded in another slot, or a typo in one joint when that one change
    explains most of a large error (at most :data:`TYPO_SHARE` of it and ``ok_mm`` / ``ok_deg`` left); "" when
    only the tilt is off.

    Args:
        slots, qs, p_world, tilt_deg: every contact's slot, joint values [rad], suction point [m, world] and axis
            angle from the table's [deg].
        targets: where the grid puts each contact [m, world], shape (N, 3).
        grid_points: the grid's contact point of every slot.
        suspects: indices of the contacts to explain.
        axis: the table's suction axis; flag_mm, flag_deg: the flag thresholds; ok_mm, ok_deg: the never-flagged
            ones.
        labels: how each contact is named.
    """
    from ur3hanoi.station.grid import pose_label

    dup = duplicates(slots, qs, [False] * len(slots))
    swaps = find_swaps(slots, p_world, grid_points, suspects, flag_mm)
    out: dict[int, str] = {}
    for i in suspects:
        err = float(np.linalg.norm(p_world[i] - targets[i])) * 1e3
        if i in dup:
            out[i] = f"it holds the joint values of {labels[dup[i]]}: a copied entry"
        elif i in swaps:
            j, di, dj = swaps[i]
            out[i] = (f"{swap_kind(slots[i], slots[j])} with {labels[j]}: exchanged, both are within "
                      f"{max(di, dj):.1f} mm of the grid")
        elif err <= flag_mm:
            out[i] = ""
        else:
            slot, d = nearest_slot(p_world[i], grid_points)
            typo = joint_typo_point(robot, T_world_base, qs[i], targets[i], axis, ok_mm, ok_deg)
            explains = (typo is not None and typo.residual_mm <= min(ok_mm, TYPO_SHARE * err)
                        and typo.residual_deg <= ok_deg)
            if slot != slots[i] and d <= flag_mm and tilt_deg[i] <= flag_deg and not (
                    explains and typo is not None and typo.residual_mm < d):
                out[i] = f"it is {d:.1f} mm from where the grid puts {pose_label(*slot)}: recorded in the wrong slot?"
            elif explains and typo is not None:
                out[i] = (f"likely {typo.describe()} (that one change leaves {typo.residual_mm:.1f} mm of the "
                          f"{err:.1f} mm)")
            elif typo is not None:
                out[i] = (f"no single joint explains it (the best, joint {typo.joint + 1}, leaves "
                          f"{typo.residual_mm:.1f} mm of {err:.1f} mm): re-record it")
            else:
                out[i] = "no single joint explains it: re-record it"
    return out


__all__ = [
    "JOINT_LABELS",
    "MIN_SIGN_DEG",
    "MIN_TYPO_DEG",
    "TYPO_SHARE",
    "JointTypo",
    "angle_text",
    "diagnose",
    "diagnose_contacts",
    "duplicates",
    "find_swaps",
    "joint_typo",
    "joint_typo_point",
    "nearest_slot",
    "swap_kind",
]
