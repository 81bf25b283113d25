"""Jogging for practice where there is no pendant: the suction point moved in Cartesian steps in the station's
frame, or turned about the tool's own axis, by closed-form IK on the arm's current configuration branch.

Each key press is one step: the target is the current suction point (FK of the published pose) moved by the step,
its joint angles the closed-form IK solution on the branch the arm is on (shoulder, elbow, wrist), each joint the
2pi-equivalent nearest the current one. The step is sent as one joint move at :data:`JOG_SPEED_RAD_S` and
:data:`JOG_ACCEL_RAD_S2`, a tenth or less of the lab's 4 rad/s and 4 rad/s^2, so a 20 mm step takes about a second.

A step is refused, with its reason, when it would leave the reachable workspace (no IK solution), need another
branch (the arm would flip), leave the joint limits, put the suction point below the table top, or turn some joint
by more than :data:`MAX_STEP_JOINT_DEG` (next to a singularity the solution on the same branch jumps: a small step
would swing the wrist half a turn).

``go`` names a whole pose instead: the base calibration's pose above a slot (its approach height over where it
puts the block), on the current branch, as one joint move at the same caps.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.ik import analytic_ik, branch_of, nearest_equivalent
from ur3hanoi.robot.model import Ur3Model, load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, H_world_tcp, table_z

JOG_STEPS_MM: tuple[float, ...] = (1.0, 5.0, 20.0)
"""[mm] the step sizes (keys 1, 2, 3); a turn steps by the same number of degrees."""
JOG_SPEED_RAD_S = 0.35
"""[rad/s] joint speed of every jog move (20 deg/s; the lab's program sends 4 rad/s)."""
JOG_ACCEL_RAD_S2 = 0.7
"""[rad/s^2] joint acceleration of every jog move (the lab's program sends 4 rad/s^2)."""
MAX_STEP_JOINT_DEG = 25.0
"""[deg] a step that needs a larger motion of any joint is refused (near a singularity)."""
_BRANCH_NAMES = ("shoulder", "elbow", "wrist")


@dataclass(frozen=True)
class JogTarget:
    """A jog step's outcome: the joint target ``q`` [rad] (None when refused), the suction point it goes to
    ``p_world_m`` (3,) [m, world], and ``reason`` ("" unless refused)."""

    q: FloatArray | None
    p_world_m: FloatArray
    reason: str

    @property
    def refused(self) -> bool:
        return self.q is None


def _rigid_inverse(H: FloatArray) -> FloatArray:
    out = np.eye(4)
    out[:3, :3] = H[:3, :3].T
    out[:3, 3] = -H[:3, :3].T @ H[:3, 3]
    return out


def _rot_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    R = np.eye(4)
    R[:2, :2] = [[c, -s], [s, c]]
    return R


class Jogger:
    """FK and IK steps of the arm of ``station`` (robot base, tool, limits, table)."""

    def __init__(self, station: Station) -> None:
        self.station = station
        self.robot: Ur3Model = load_ur3(station.tool, station.limits, station.robot)
        self.H_world_base = station.H_world_base
        self.H_base_world = _rigid_inverse(self.H_world_base)
        self.table_z = table_z(station)

    def H_world_tcp(self, q: FloatArray) -> FloatArray:
        """The suction point's pose in world at joint angles ``q`` [rad] (4x4)."""
        return np.asarray(self.H_world_base @ self.robot.fk_matrix(np.asarray(q, dtype=float), "tcp"), dtype=float)

    def _solve(self, q: FloatArray, H_world_tcp: FloatArray, what: str, max_joint_deg: float | None) -> JogTarget:
        p = H_world_tcp[:3, 3].copy()

        def refuse(reason: str) -> JogTarget:
            return JogTarget(None, p, f"{what} refused: {reason}")

        if p[2] < self.table_z:
            return refuse(f"the suction point would be {1e3 * (self.table_z - p[2]):.1f} mm below the table top")
        H_base_tool0 = self.H_base_world @ H_world_tcp @ self.robot.H_tcp_tool0
        solutions = analytic_ik(H_base_tool0, dh=self.robot.dh)
        if not solutions:
            return refuse("the suction point would leave the arm's reachable workspace (no IK solution)")
        branch = branch_of(q, self.robot.dh)
        if branch not in solutions:
            nearest = min(solutions, key=lambda b: sum(x != y for x, y in zip(b, branch, strict=True)))
            flips = [name for name, a, b in zip(_BRANCH_NAMES, branch, nearest, strict=True) if a != b]
            return refuse(f"the IK solution would switch the arm to another configuration ({', '.join(flips)} "
                          "flipped): move elsewhere first, or turn the arm with the pendant")
        target = nearest_equivalent(solutions[branch], q, self.robot.limits)
        if target is None:
            return refuse("the IK solution is outside the joint limits")
        if max_joint_deg is not None:
            moved = np.degrees(np.abs(target - q))
            worst = int(np.argmax(moved))
            if moved[worst] > max_joint_deg:
                return refuse(f"joint {worst + 1} would turn {moved[worst]:.1f} deg for it (more than "
                              f"{max_joint_deg:g} deg): the IK would jump across a singularity to another "
                              "configuration")
        return JogTarget(target, p, "")

    def step(self, q: FloatArray, delta_world_mm: tuple[float, float, float] = (0.0, 0.0, 0.0),
             turn_deg: float = 0.0) -> JogTarget:
        """The joint target that moves the suction point by ``delta_world_mm`` [mm, world] and turns the tool by
        ``turn_deg`` [deg] about its own axis, from ``q`` [rad] (see the module docstring)."""
        q = np.asarray(q, dtype=float)
        H = self.H_world_tcp(q) @ _rot_z(math.radians(turn_deg))
        H[:3, 3] += np.asarray(delta_world_mm, dtype=float) * 1e-3
        what = (f"turn {turn_deg:+g} deg" if turn_deg else
                "step " + " ".join(f"{'xyz'[i]} {d:+g} mm" for i, d in enumerate(delta_world_mm) if d))
        return self._solve(q, H, what, MAX_STEP_JOINT_DEG)

    def go_above(self, q: FloatArray, base: Station, tower: int, height: int) -> JogTarget:
        """The joint target of ``base``'s pose above (tower, height) (0-based), on ``q``'s branch."""
        return self._solve(np.asarray(q, dtype=float), H_world_tcp(base, tower, height, ABOVE),
                           f"go to tower {tower + 1} height {height + 1} above", None)


def move_time_s(q_from: FloatArray, q_to: FloatArray) -> float:
    """How long a jog move takes [s]: the leading joint's trapezoid (or triangle) at the jog caps."""
    d = float(np.max(np.abs(np.asarray(q_to) - np.asarray(q_from))))
    v, a = JOG_SPEED_RAD_S, JOG_ACCEL_RAD_S2
    return 2.0 * math.sqrt(d / a) if d < v * v / a else d / v + v / a


__all__ = ["JOG_ACCEL_RAD_S2", "JOG_SPEED_RAD_S", "JOG_STEPS_MM", "MAX_STEP_JOINT_DEG", "JogTarget", "Jogger",
           "move_time_s"]
