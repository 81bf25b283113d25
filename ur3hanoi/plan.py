"""Motion plan of a Hanoi solve: waypoints from the table, time-parameterized by Ruckig under UR3 limits.

CONTRACT (shared with ur3hanoi.sim; keep these names and meanings):

- :class:`Phase` labels every trajectory sample.
- :class:`Trajectory` holds the samples at ``rate_hz``: ``t`` (N,) [s], ``q``/``qd``/``qdd``/``qddd`` (N, 6)
  [rad, rad/s, rad/s^2, rad/s^3], ``suction`` (N,) bool (commanded suction), ``move_index`` (N,) int (0-based
  index into ``Plan.moves``, -1 before the first move / on the way home), ``phase`` (N,) int (Phase values).
- :class:`Plan`: ``station``, ``moves`` (tuple of hanoi.Move), ``trajectory``, ``stop_and_go_duration_s``,
  ``config``.

How the motion is built (see :func:`plan_solve`):

- Each move visits home/previous -> above(src) -> on(src) -> [suction on, dwell] -> above(src) -> above(dst) ->
  on(dst) -> [suction off, dwell] -> above(dst); the plan ends at home with suction off. Joint waypoints come from
  :func:`ur3hanoi.table.generate_table` (IK on the home branch).
- Every segment is one offline Ruckig ``calculate`` (the open-source library; no cloud intermediate waypoints).
  Segments are chained: the end state of one is the start state of the next.
- Pass-through: the robot does not stop at "above" waypoints. The via velocity there is the joint velocity that
  moves the suction point straight down (descend) or straight up (lift/retreat) at a Cartesian speed ``sigma``
  [m/s]. ``sigma`` is picked per transit/carry segment from ``PlanConfig.via_fractions`` of the largest speed
  that the vertical leg can brake from without overshooting the contact pose, minimising the summed duration of
  the vertical leg, the horizontal segment and the next vertical leg (the legs decouple: a via point joins
  exactly one vertical and one horizontal segment). The minimum is found by a descent over the grid of (exit,
  entry) candidates from the fastest pair (see ``_Builder.build``). A candidate whose ``calculate`` fails is
  dropped; zero (stop-and-go) is always a candidate.
- Honest vertical approach: a straight joint-space line between above and on bends the suction point up to ~9 mm
  off the vertical on the lab stations, so each vertical leg is split at IK points on the vertical line
  (:func:`ur3hanoi.ik.solve_on_branch`) until every chord deviates <= ``chord_tol_m``; interior via velocities
  follow the line's tangent at the speed a single straight-line Ruckig profile has there. Every sample of the
  vertical phases is checked by FK against ``vertical_tol_m`` (2 mm).
- ``stop_and_go_duration_s``: the same main waypoints (home, above, on) with zero velocity at each, one Ruckig
  segment per leg (straight joint lines for the vertical legs), the same dwells and the same limits.

Limits: velocity from the UR3 datasheet (``JointLimits.ur3().v_max``: pi rad/s joints 1-3, 2pi rad/s joints 4-6);
acceleration 4/8 rad/s^2 and jerk 20/40 rad/s^3 (joints 1-3 / 4-6) are ``JointLimits`` defaults (UR does not
publish them). ``PlanConfig.speed`` scales all three; each can be overridden.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from enum import IntEnum
from functools import cached_property, lru_cache
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from ruckig import InputParameter, Result, Ruckig
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.grid import ABOVE, ON, R_world_tcp_down, T_base_tcp, block_center_world, contact_point_world, table_z
from ur3hanoi.hanoi import Move, check_sequence, solve_hanoi, stacks_before_moves
from ur3hanoi.ik import analytic_ik, branch_of, nearest_equivalent
from ur3hanoi.robot import N_JOINTS, T_BASELINK_BASE, Ur3Model, dh_fk, load_ur3
from ur3hanoi.station import Station
from ur3hanoi.table import generate_table

LIMIT_RTOL = 1e-6  # relative tolerance of the velocity/acceleration/jerk checks
POSITION_ATOL = 1e-9  # [rad] slack of the joint position limit check
DEFAULT_VIA_FRACTIONS: tuple[float, ...] = (1.0, 0.8, 0.6, 0.4, 0.2, 0.0)


class Phase(IntEnum):
    """What the robot is doing at a trajectory sample."""

    TRANSIT = 0  # home/previous place -> above(src), empty cup
    DESCEND_PICK = 1  # above(src) -> on(src), empty cup
    GRASP_DWELL = 2  # at on(src), suction on, waiting for the vacuum
    LIFT = 3  # on(src) -> above(src), carrying
    CARRY = 4  # above(src) -> above(dst), carrying
    DESCEND_PLACE = 5  # above(dst) -> on(dst), carrying
    RELEASE_DWELL = 6  # at on(dst), suction off, waiting for the release
    RETREAT = 7  # on(dst) -> above(dst), empty cup
    HOME = 8  # last above -> home, suction off

    @property
    def carrying(self) -> bool:
        """True when a block must be held during this phase (suction feedback is checked)."""
        return self in (Phase.LIFT, Phase.CARRY, Phase.DESCEND_PLACE)


VERTICAL_PHASES = (Phase.DESCEND_PICK, Phase.LIFT, Phase.DESCEND_PLACE, Phase.RETREAT)
DWELL_PHASES = (Phase.GRASP_DWELL, Phase.RELEASE_DWELL)
# Commanded suction: on from the grasp dwell until the block is on its destination.
SUCTION_PHASES = (Phase.GRASP_DWELL, Phase.LIFT, Phase.CARRY, Phase.DESCEND_PLACE)


@dataclass(frozen=True)
class Trajectory:
    """Sampled joint trajectory at ``rate_hz`` (see the module docstring for array shapes and units).

    Samples are uniform, ``t[i] = i / rate_hz``; the last sample is the first one at or after the end of the
    motion, so it holds the final (home) state exactly.
    """

    rate_hz: float
    t: FloatArray
    q: FloatArray
    qd: FloatArray
    qdd: FloatArray
    qddd: FloatArray
    suction: npt.NDArray[np.bool_]
    move_index: npt.NDArray[np.int_]
    phase: npt.NDArray[np.int_]

    @property
    def duration_s(self) -> float:
        return float(self.t[-1] - self.t[0])


@dataclass(frozen=True)
class KinematicLimits:
    """Per-joint limits used for planning [rad/s, rad/s^2, rad/s^3], already scaled by ``PlanConfig.speed``."""

    v_max: FloatArray
    a_max: FloatArray
    j_max: FloatArray


@dataclass(frozen=True)
class PlanConfig:
    """Planner settings. ``speed`` scales velocity, acceleration and jerk limits (0 < speed <= 1).

    Attributes:
        speed: scale of v_max, a_max and j_max (0 < speed <= 1).
        rate_hz: sample rate [Hz]; 125 (CB3) or 500 (e-Series), any positive rate is accepted.
        dwell_s: time at rest at each contact pose for the suction to build up / release [s].
        v_max, a_max, j_max: per-joint overrides [rad/s, rad/s^2, rad/s^3] (None: the station's JointLimits).
        pass_through: False plans stop-and-go (zero velocity at every waypoint).
        via_fractions: candidate fractions of the largest feasible vertical speed at the "above" via points.
        vertical_tol_m: allowed distance [m] of the suction point from the vertical line in vertical phases.
        clearance_m: required clearance [m] of the carried block from every other block.
        check_collisions: run the Pinocchio/coal clearance checks (slower; limits are always checked).
        collision_rate_hz: coarse rate [Hz] of the clearance check; refined to every sample where the margin is
            not provably enough (see :class:`CollisionScene`).
        raise_on_violation: raise PlanError on the first violation list (False: return it in Plan.violations).
    """

    speed: float = 1.0
    rate_hz: float = 125.0
    dwell_s: float = 0.3
    v_max: tuple[float, ...] | None = None
    a_max: tuple[float, ...] | None = None
    j_max: tuple[float, ...] | None = None
    pass_through: bool = True
    via_fractions: tuple[float, ...] = DEFAULT_VIA_FRACTIONS
    vertical_tol_m: float = 0.002
    clearance_m: float = 0.005
    check_collisions: bool = True
    collision_rate_hz: float = 25.0
    raise_on_violation: bool = True

    def validate(self) -> None:
        """Raise PlanError naming the first invalid setting."""
        if not (math.isfinite(self.speed) and 0.0 < self.speed <= 1.0):
            raise PlanError(f"speed = {self.speed!r} is invalid: expected 0 < speed <= 1")
        if not (math.isfinite(self.rate_hz) and self.rate_hz > 0.0):
            raise PlanError(f"rate = {self.rate_hz!r} Hz is invalid: expected a positive rate (125 or 500)")
        if not (math.isfinite(self.dwell_s) and self.dwell_s >= 0.0):
            raise PlanError(f"dwell = {self.dwell_s!r} s is invalid: expected >= 0")
        for name in ("v_max", "a_max", "j_max"):
            v = getattr(self, name)
            if v is not None and (len(v) != N_JOINTS or not all(math.isfinite(x) and x > 0 for x in v)):
                raise PlanError(f"{name} = {v!r} is invalid: expected {N_JOINTS} positive numbers")
        if not self.via_fractions or not all(0.0 <= f <= 1.0 for f in self.via_fractions):
            raise PlanError(f"via_fractions = {self.via_fractions!r} is invalid: expected values in [0, 1]")
        for name in ("collision_rate_hz", "vertical_tol_m", "clearance_m"):
            x = getattr(self, name)
            if not (math.isfinite(x) and x > 0.0):  # NaN compares False everywhere: test finiteness explicitly
                raise PlanError(f"{name} = {x!r} is invalid: expected a finite number > 0")

    def limits(self, station: Station) -> KinematicLimits:
        """The scaled planning limits for ``station``."""
        lim = station.limits
        v = np.asarray(self.v_max if self.v_max is not None else lim.v_max, dtype=float)
        a = np.asarray(self.a_max if self.a_max is not None else lim.a_max, dtype=float)
        j = np.asarray(self.j_max if self.j_max is not None else lim.j_max, dtype=float)
        return KinematicLimits(v_max=v * self.speed, a_max=a * self.speed, j_max=j * self.speed)


@dataclass(frozen=True)
class Segment:
    """One Ruckig segment (or a dwell) of the plan.

    ``trajectory`` is the Ruckig trajectory of the segment (time 0 = ``t_start``), None for a dwell at rest at
    ``q_start``. For a vertical leg ``path`` is set and ``trajectory`` is the 1-DoF Ruckig trajectory of the path
    coordinate s [m] (see :class:`VerticalPath`); otherwise it is 6-DoF in joint space. ``target`` names the
    waypoint reached at the segment's end (1-based tower/height).
    """

    phase: Phase
    move_index: int
    t_start: float  # [s]
    duration: float  # [s]
    q_start: FloatArray  # [rad]
    q_end: FloatArray  # [rad]
    v_start: FloatArray  # [rad/s]
    v_end: FloatArray  # [rad/s]
    target: str
    trajectory: RuckigTrajectory | None = None
    path: VerticalPath | None = None

    @property
    def t_end(self) -> float:
        return self.t_start + self.duration


@dataclass(frozen=True)
class Plan:
    """A planned Hanoi solve.

    Attributes (beyond the contract's ``station``, ``moves``, ``trajectory``, ``stop_and_go_duration_s``,
    ``config``):
        segments: the chained Ruckig segments and dwells.
        limits: the planning limits actually used.
        violations: safety check failures (empty for a valid plan; non-empty only if not raise_on_violation).
        duration_s: exact cycle time [s] (the sampled trajectory ends on the first sample at or after it).
        dwell_total_s: time at rest in the grasp/release dwells [s].
        stop_and_go_motion_s: stop-and-go cycle minus the same dwells [s].
        start, end, n_blocks: the instance (0-based towers).
        timings_s: wall-clock planning times [s]: "ruckig" (calculate calls), "sampling", "checks", "collision".
    """

    station: Station
    moves: tuple[Move, ...]
    trajectory: Trajectory
    stop_and_go_duration_s: float
    config: PlanConfig
    segments: tuple[Segment, ...] = ()
    limits: KinematicLimits | None = None
    violations: tuple[str, ...] = ()
    duration_s: float = 0.0
    dwell_total_s: float = 0.0
    stop_and_go_motion_s: float = 0.0
    start: int = 0
    end: int = 0
    n_blocks: int = 0
    timings_s: dict[str, float] = field(default_factory=dict)

    @property
    def motion_s(self) -> float:
        """Cycle time minus the dwells [s]."""
        return self.duration_s - self.dwell_total_s

    @property
    def motion_saving(self) -> float:
        """Relative motion-time saving over stop-and-go (0.15 = 15 % faster)."""
        return 1.0 - self.motion_s / self.stop_and_go_motion_s if self.stop_and_go_motion_s > 0 else 0.0

    def to_json_dict(self) -> dict[str, Any]:
        """JSON-ready summary; towers, heights and blocks numbered from 1 (block 1 = bottom/largest)."""
        tr = self.trajectory
        lim = self.limits

        def vec(a: FloatArray) -> list[float]:
            return [float(x) for x in a]

        return {
            "station": self.station.name,
            "start_tower": self.start + 1,
            "end_tower": self.end + 1,
            "blocks": self.n_blocks,
            "moves": [m.as_lab_dict() for m in self.moves],
            "duration_s": self.duration_s,
            "stop_and_go_duration_s": self.stop_and_go_duration_s,
            "motion_s": self.motion_s,
            "stop_and_go_motion_s": self.stop_and_go_motion_s,
            "dwell_s": self.config.dwell_s,
            "speed": self.config.speed,
            "rate_hz": tr.rate_hz,
            "samples": len(tr.t),
            "max_abs_velocity": vec(np.max(np.abs(tr.qd), axis=0)),
            "max_abs_acceleration": vec(np.max(np.abs(tr.qdd), axis=0)),
            "max_abs_jerk": vec(np.max(np.abs(tr.qddd), axis=0)),
            "velocity_limit": vec(lim.v_max) if lim is not None else [],
            "acceleration_limit": vec(lim.a_max) if lim is not None else [],
            "jerk_limit": vec(lim.j_max) if lim is not None else [],
            "violations": list(self.violations),
            "planning_time_s": dict(self.timings_s),
        }


# ------------------------------------------------------------------------------------------------- waypoints


@dataclass(frozen=True)
class VerticalPath:
    """The vertical line of one grid slot as a joint-space path ``q(s)``, ``s`` [m] = distance below "above".

    Nodes every <= ``node_step_m`` by closed-form IK on the home branch (the end nodes are the table's entries);
    ``q(s)`` between nodes is the cubic Hermite interpolant of (q, dq/ds), accurate to ~1e-10 rad.

    Attributes:
        s: (M,) node abscissae [m], 0 = above, length_m = on.
        q: (M, 6) joint angles [rad].
        dq: (M, 6) dq/ds [rad/m] (exact: J^-1 of a straight-down unit twist).
        ddq, dddq: (M, 6) d2q/ds2 [rad/m^2], d3q/ds3 [rad/m^3] by finite differences of dq/ds.
        length_m: approach length [m].
    """

    s: FloatArray
    q: FloatArray
    dq: FloatArray
    ddq: FloatArray
    dddq: FloatArray
    length_m: float

    @cached_property
    def derivative_bounds(self) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Per-joint ``max |d^k q / ds^k|`` over the nodes for k = 1, 2, 3 (computed once per path: the waypoints,
        and so their paths, are cached per station while every plan derives its path limits from these)."""
        return (np.max(np.abs(self.dq), axis=0), np.max(np.abs(self.ddq), axis=0),
                np.max(np.abs(self.dddq), axis=0))

    def evaluate(self, s: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(q, dq/ds, d2q/ds2, d3q/ds3) at ``s`` [m] (clamped to [0, length_m]): a cubic Hermite spline through
        the IK nodes for q and dq/ds, linear for the higher derivatives."""
        q, dq, ddq, dddq = self.evaluate_many(np.array([s], dtype=float))
        return q[0], dq[0], ddq[0], dddq[0]

    def evaluate_many(self, s: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`evaluate` at every ``s`` (N,) [m] at once: four (N, 6) arrays, with the same arithmetic."""
        s = np.minimum(np.maximum(s, 0.0), self.length_m)
        k = np.minimum(np.searchsorted(self.s, s, side="right") - 1, len(self.s) - 2)
        h = (self.s[k + 1] - self.s[k])[:, None]
        u = (s[:, None] - self.s[k][:, None]) / h
        q0, q1, m0, m1 = self.q[k], self.q[k + 1], self.dq[k] * h, self.dq[k + 1] * h
        u2, u3 = u * u, u * u * u
        q = (2 * u3 - 3 * u2 + 1) * q0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * q1 + (u3 - u2) * m1
        dq = ((6 * u2 - 6 * u) * q0 + (3 * u2 - 4 * u + 1) * m0 + (-6 * u2 + 6 * u) * q1 + (3 * u2 - 2 * u) * m1) / h
        ddq = (1 - u) * self.ddq[k] + u * self.ddq[k + 1]
        dddq = (1 - u) * self.dddq[k] + u * self.dddq[k + 1]
        return q, dq, ddq, dddq


@dataclass(frozen=True)
class Waypoints:
    """Joint waypoints of a station: home, the table ``q[tower, height, k]`` and the vertical paths."""

    q_home: FloatArray
    table: FloatArray
    vertical: tuple[tuple[VerticalPath, ...], ...]  # [tower][height]


def _tangent_down(robot: Ur3Model, R_world_base: FloatArray, q: FloatArray) -> FloatArray:
    """Joint velocity moving the TCP at 1 m/s along world -z without rotating (J^-1 of the twist)."""
    J = robot.frame_jacobian_local(q, "tcp")
    R_world_tcp = R_world_base @ robot.fk(q, "tcp").rotation
    twist = np.concatenate([R_world_tcp.T @ np.array([0.0, 0.0, -1.0]), np.zeros(3)])
    return np.linalg.solve(J, twist)


def _line_ik(robot: Ur3Model, station: Station, tower: int, height: int) -> Callable[[float, FloatArray], FloatArray]:
    """``ik(s, q_ref)``: closed-form IK [rad] of the suction point ``s`` [m] below the above pose of (tower, height),
    on home's branch, nearest ``q_ref``."""
    T_above = T_base_tcp(station, tower, height, ABOVE)
    R_base_world = station.T_world_base.rotation.T
    branch = branch_of(station.q_home_array)

    def ik(s: float, q_ref: FloatArray) -> FloatArray:
        T = pin.SE3(T_above.rotation, T_above.translation - R_base_world @ np.array([0.0, 0.0, s]))
        sols = analytic_ik(T * robot.T_tcp_tool0, only=branch)
        q = nearest_equivalent(sols[branch], q_ref, station.limits) if branch in sols else None
        if q is None:
            raise PlanError(f"tower {tower + 1} height {height + 1}: the vertical line {s * 1e3:.1f} mm below the "
                            "above pose has no IK solution on home's branch within the joint limits")
        return q

    return ik


@lru_cache(maxsize=32)
def build_waypoints(station: Station, node_step_m: float = 0.002) -> Waypoints:
    """Table by IK on the home branch, plus the vertical path of every slot. Cached per station."""
    table = generate_table(station)
    robot = load_ur3(station.tool, station.limits)
    R_world_base = station.T_world_base.rotation
    h_fd = 1e-3  # [m] finite-difference step of the higher path derivatives
    L = station.approach
    n = max(2, math.ceil(L / node_step_m)) + 1
    s_nodes = np.linspace(0.0, L, n)
    vertical = []
    for t in range(station.n_towers):
        col = []
        for h in range(station.n_heights):
            ik = _line_ik(robot, station, t, h)
            q_nodes = np.empty((n, N_JOINTS))
            q_ref = table.q[t, h, ABOVE]
            for k, s in enumerate(s_nodes):
                q_nodes[k] = q_ref = ik(float(s), q_ref)
            # The ends are the table's entries exactly (they agree with closed-form IK to ~1e-11 rad).
            q_nodes[0], q_nodes[-1] = table.q[t, h, ABOVE], table.q[t, h, ON]
            dq = np.array([_tangent_down(robot, R_world_base, q) for q in q_nodes])
            ddq = np.empty_like(dq)
            dddq = np.empty_like(dq)
            for k, (s, q) in enumerate(zip(s_nodes, q_nodes, strict=True)):
                dm = _tangent_down(robot, R_world_base, ik(float(s) - h_fd, q))
                dp = _tangent_down(robot, R_world_base, ik(float(s) + h_fd, q))
                ddq[k] = (dp - dm) / (2 * h_fd)
                dddq[k] = (dp - 2 * dq[k] + dm) / (h_fd * h_fd)
            col.append(VerticalPath(s=s_nodes, q=q_nodes, dq=dq, ddq=ddq, dddq=dddq, length_m=L))
        vertical.append(tuple(col))
    return Waypoints(q_home=station.q_home_array, table=table.q, vertical=tuple(vertical))


# -------------------------------------------------------------------------------------------------- ruckig


def _aslist(x: FloatArray | list[float]) -> list[float]:
    return x.tolist() if isinstance(x, np.ndarray) else x


class _Ruckig:
    """One offline Ruckig instance with the given limits; counts its own time for the benchmark."""

    def __init__(self, v_max: FloatArray, a_max: FloatArray, j_max: FloatArray) -> None:
        self.dofs = len(v_max)
        self.otg = Ruckig(self.dofs)
        self.inp = InputParameter(self.dofs)
        self.inp.max_velocity = [float(x) for x in v_max]
        self.inp.max_acceleration = [float(x) for x in a_max]
        self.inp.max_jerk = [float(x) for x in j_max]
        self.seconds = 0.0

    def calc(self, q0: FloatArray | list[float], v0: FloatArray | list[float], a0: FloatArray | list[float],
             q1: FloatArray | list[float], v1: FloatArray | list[float],
             a1: FloatArray | list[float]) -> RuckigTrajectory | None:
        """Time-optimal (time-synchronized) segment between two states; None if Ruckig fails.

        States may be given as lists (callers that try many candidates convert them once).
        """
        t0 = time.perf_counter()
        inp = self.inp
        inp.current_position = _aslist(q0)
        inp.current_velocity = _aslist(v0)
        inp.current_acceleration = _aslist(a0)
        inp.target_position = _aslist(q1)
        inp.target_velocity = _aslist(v1)
        inp.target_acceleration = _aslist(a1)
        traj = RuckigTrajectory(self.dofs)
        try:
            result = self.otg.calculate(inp, traj)
        except RuntimeError:  # RuckigError: a state outside the limits (rounding at a via point)
            result = Result.ErrorInvalidInput
        self.seconds += time.perf_counter() - t0
        # Offline calculate reports success as Working (Finished only for a zero-length segment).
        if result not in (Result.Working, Result.Finished):
            return None
        return traj


def _within(traj: RuckigTrajectory, lo: float, hi: float) -> bool:
    """True when the 1-DoF trajectory stays in [lo, hi] (no push past the contact pose or above the above pose)."""
    e = traj.position_extrema[0]
    return lo - 1e-12 <= e.min and e.max <= hi + 1e-12


def _braking_speed(dist: float, a: float, j: float) -> float:
    """Largest speed a jerk-limited (a, j) profile starting at zero acceleration stops from within ``dist``."""
    # Stopping distance d(v): v*sqrt(v/j) if the profile never reaches a (v <= a^2/j), else v^2/(2a) + v*a/(2j).
    v_knee = a * a / j
    if v_knee * math.sqrt(v_knee / j) >= dist:
        return (dist * dist * j) ** (1.0 / 3.0)
    b = a / (2 * j)
    return (-b + math.sqrt(b * b + 2 * dist / a)) * a


@dataclass(frozen=True)
class PathLimits:
    """Limits of the path coordinate s of a vertical leg [m/s, m/s^2, m/s^3].

    They keep every joint within its limits through the chain rule ``qd = q1 sd``, ``qdd = q2 sd^2 + q1 sdd``,
    ``qddd = q3 sd^3 + 3 q2 sd sdd + q1 sddd`` (``qk`` = k-th derivative of q(s)). Budget split, per joint, with
    ``Dk = 1.05 max |qk|`` over the path: ``D1 v <= v_max``; ``D2 v^2 <= 0.4 a_max`` and ``D1 a`` takes the rest;
    ``D3 v^3 <= 0.3 j_max``, ``3 D2 v a <= 0.4 j_max`` and ``D1 j`` takes the rest.
    """

    v: float
    a: float
    j: float

    @classmethod
    def for_path(cls, path: VerticalPath, lim: KinematicLimits) -> PathLimits:
        D1, D2, D3 = (1.05 * x + 1e-12 for x in path.derivative_bounds)
        v = float(np.min(np.minimum.reduce([lim.v_max / D1, np.sqrt(0.4 * lim.a_max / D2),
                                            np.cbrt(0.3 * lim.j_max / D3)])))
        a = float(np.min(np.minimum((lim.a_max - D2 * v * v) / D1, 0.4 * lim.j_max / (3 * D2 * v))))
        j = float(np.min((lim.j_max - D3 * v**3 - 3 * D2 * v * a) / D1))
        return cls(v, a, j)


@dataclass(frozen=True)
class _Leg:
    """A vertical leg's duration [s] for one via speed sigma [m/s] (descend and lift are time-reverses)."""

    sigma: float
    duration: float


Slot = tuple[int, int]


class _LegCandidates:
    """A slot's candidate legs, fastest via speed first; a leg's Ruckig problem is solved on first use (the search
    in ``_Builder.build`` usually needs only the fastest two or three). Failed candidates are dropped."""

    def __init__(self, speeds: Sequence[float], solve: Callable[[float], RuckigTrajectory | None],
                 solved: Sequence[_Leg] = ()) -> None:
        self._speeds = iter(speeds)
        self._solve = solve
        self._legs: list[_Leg] = list(solved)

    def get(self, i: int) -> _Leg | None:
        """The i-th feasible candidate (None: fewer than i + 1 exist)."""
        while len(self._legs) <= i:
            sigma = next(self._speeds, None)
            if sigma is None:
                return None
            traj = self._solve(sigma)
            if traj is not None:
                self._legs.append(_Leg(sigma, traj.duration))
        return self._legs[i]

    def count(self) -> int:
        """Number of feasible candidates (solves them all)."""
        while self.get(len(self._legs)) is not None:
            pass
        return len(self._legs)


_AT_REST = _LegCandidates([], lambda _: None, [_Leg(0.0, 0.0)])  # home: at rest, no vertical leg


class _Builder:
    """Chains Ruckig segments for a move sequence (pass-through or stop-and-go)."""

    def __init__(self, station: Station, wp: Waypoints, config: PlanConfig, pass_through: bool = True) -> None:
        self.wp = wp
        self.config = config
        self.pass_through = pass_through and config.pass_through
        self.limits = config.limits(station)
        self.rk = _Ruckig(self.limits.v_max, self.limits.a_max, self.limits.j_max)
        self._legs: dict[Slot, _LegCandidates] = {}
        self._path_rk: dict[Slot, tuple[_Ruckig, PathLimits]] = {}
        # Memos of identical Ruckig problems: a Hanoi solve revisits the same few slot pairs over and over (1023
        # moves use at most n_towers * n_heights slots), and each problem is deterministic in its key, so reusing
        # the trajectory object gives exactly the same segments. Shared trajectories are never mutated.
        self._path_memo: dict[tuple[Slot, float, bool], RuckigTrajectory | None] = {}
        self._horizontal_memo: dict[tuple[Slot | None, bytes, Slot | None, bytes],
                                     tuple[float, float, RuckigTrajectory]] = {}

    @property
    def ruckig_seconds(self) -> float:
        return self.rk.seconds + sum(r.seconds for r, _ in self._path_rk.values())

    def _path(self, slot: Slot) -> tuple[VerticalPath, _Ruckig, PathLimits]:
        vp = self.wp.vertical[slot[0]][slot[1]]
        if slot not in self._path_rk:
            pl = PathLimits.for_path(vp, self.limits)
            self._path_rk[slot] = (_Ruckig(np.array([pl.v]), np.array([pl.a]), np.array([pl.j])), pl)
        rk, pl = self._path_rk[slot]
        return vp, rk, pl

    def path_traj(self, slot: Slot, sigma: float, down: bool) -> RuckigTrajectory | None:
        """1-DoF Ruckig of s: down = above (entering at sigma [m/s]) -> on at rest; else on -> above (leaving).

        Memoized per (slot, sigma, down): :meth:`legs` already solves every candidate descend once.
        """
        key = (slot, sigma, down)
        if key not in self._path_memo:
            self._path_memo[key] = self._path_traj(slot, sigma, down)
        return self._path_memo[key]

    def _path_traj(self, slot: Slot, sigma: float, down: bool) -> RuckigTrajectory | None:
        vp, rk, _ = self._path(slot)
        z = [0.0]
        L = vp.length_m
        traj = rk.calc(z, [sigma], z, [L], z, z) if down else rk.calc([L], z, z, z, [-sigma], z)
        if traj is None or not _within(traj, 0.0, L):
            return None
        return traj

    def legs(self, slot: Slot) -> _LegCandidates:
        """Candidate via speeds of a slot's vertical leg, fastest first, with their durations (cached per slot)."""
        if slot not in self._legs:
            vp, _, pl = self._path(slot)
            smax = 0.999 * min(pl.v, _braking_speed(vp.length_m, pl.a, pl.j))
            fractions = self.config.via_fractions if self.pass_through else (0.0,)
            self._legs[slot] = _LegCandidates([f * smax for f in sorted({*fractions, 0.0}, reverse=True)],
                                              lambda sigma: self.path_traj(slot, sigma, down=True))
        return self._legs[slot]

    def via_state(self, slot: Slot | None, sigma: float, down: bool) -> tuple[FloatArray, FloatArray]:
        """Joint (velocity, acceleration) at the above pose of ``slot`` moving along its line at sigma [m/s]."""
        if slot is None or sigma == 0.0:
            return np.zeros(N_JOINTS), np.zeros(N_JOINTS)
        vp = self.wp.vertical[slot[0]][slot[1]]
        v = sigma * vp.dq[0] if down else -sigma * vp.dq[0]
        return v, sigma * sigma * vp.ddq[0]  # the s-acceleration is zero at the via point

    def build(self, moves: Sequence[Move]) -> list[Segment]:
        """The chained segments of ``moves``."""
        wp, dwell = self.wp, self.config.dwell_s
        zero = np.zeros(N_JOINTS)
        segs: list[Segment] = []
        t_now = 0.0

        def add(phase: Phase, mi: int, q0: FloatArray, v0: FloatArray, q1: FloatArray, v1: FloatArray,
                traj: RuckigTrajectory | None, duration: float, target: str,
                path: VerticalPath | None = None) -> None:
            nonlocal t_now
            segs.append(Segment(phase, mi, t_now, duration, q0, q1, v0, v1, target, traj, path))
            t_now += duration

        def horizontal(q0: FloatArray, slot0: Slot | None, q1: FloatArray,
                       slot1: Slot | None) -> tuple[float, float, RuckigTrajectory]:
            """Best (sigma0, sigma1, traj): slot0 is left upward, slot1 entered downward (None: at rest).

            Memoized: the key holds every input of the problem (the candidate via states follow from the slots).
            """
            key = (slot0, q0.tobytes(), slot1, q1.tobytes())
            if key not in self._horizontal_memo:
                self._horizontal_memo[key] = horizontal_uncached(q0, slot0, q1, slot1)
            return self._horizontal_memo[key]

        def horizontal_uncached(q0: FloatArray, slot0: Slot | None, q1: FloatArray,
                                slot1: Slot | None) -> tuple[float, float, RuckigTrajectory]:
            c0 = self.legs(slot0) if slot0 is not None else _AT_REST
            c1 = self.legs(slot1) if slot1 is not None else _AT_REST
            # Candidate states as lists (converted once per candidate, not per Ruckig call).
            q0l, q1l = q0.tolist(), q1.tolist()
            starts: dict[int, list[list[float]]] = {}
            ends: dict[int, list[list[float]]] = {}
            tried: dict[tuple[int, int], tuple[float, RuckigTrajectory | None]] = {}

            def cost(i: int, j: int) -> float:
                """Summed duration of exit leg i, the connection and entry leg j (inf: a leg or Ruckig failed)."""
                if (i, j) not in tried:
                    l0, l1 = c0.get(i), c1.get(j)
                    traj = None
                    if l0 is not None and l1 is not None:
                        if i not in starts:
                            starts[i] = [x.tolist() for x in self.via_state(slot0, l0.sigma, down=False)]
                        if j not in ends:
                            ends[j] = [x.tolist() for x in self.via_state(slot1, l1.sigma, down=True)]
                        traj = self.rk.calc(q0l, *starts[i], q1l, *ends[j])
                    # A failed calculate drops the candidate (the next, smaller via speed is tried instead).
                    tried[(i, j)] = (math.inf, None) if traj is None or l0 is None or l1 is None else (
                        l0.duration + traj.duration + l1.duration, traj)
                return tried[(i, j)][0]

            # Descent over the (exit speed, entry speed) candidate grid from the fastest pair, stepping to the best
            # improving 4-neighbour: the summed duration is unimodal over this grid in practice (the optimum has one
            # of the two speeds at its largest candidate), and the descent found the same optimum as the full
            # 6 x 6 search on every connection of the lab stations (all pairs, N = 1..3) and of a 10-level grid
            # (N = 1..7), with ~1/7 of the Ruckig calls.
            cur = (0, 0)
            while True:
                i, j = cur
                nbrs = [(i + di, j + dj) for di, dj in ((1, 0), (-1, 0), (0, 1), (0, -1))
                        if i + di >= 0 and j + dj >= 0 and c0.get(i + di) is not None and c1.get(j + dj) is not None]
                nxt = min(nbrs, key=lambda ij: cost(*ij), default=cur)
                if not cost(*nxt) < cost(*cur):
                    break
                cur = nxt
            if math.isinf(cost(*cur)):  # no feasible candidate near the fastest pair: try them all
                cur = min(itertools.product(range(c0.count()), range(c1.count())), key=lambda ij: cost(*ij),
                          default=cur)
            traj = tried[cur][1]
            if traj is None:
                raise PlanError(f"Ruckig could not connect {np.round(q0, 4).tolist()} to {np.round(q1, 4).tolist()}")
            l0, l1 = c0.get(cur[0]), c1.get(cur[1])
            assert l0 is not None and l1 is not None
            return l0.sigma, l1.sigma, traj

        def vertical(phase: Phase, mi: int, slot: Slot, sigma: float, down: bool) -> None:
            traj = self.path_traj(slot, sigma, down)
            if traj is None:
                raise PlanError(f"Ruckig failed on the vertical leg of tower {slot[0] + 1} height {slot[1] + 1}")
            vp = wp.vertical[slot[0]][slot[1]]
            q0, q1 = (vp.q[0], vp.q[-1]) if down else (vp.q[-1], vp.q[0])
            v0 = self.via_state(slot, sigma, True)[0] if down else zero
            v1 = zero if down else self.via_state(slot, sigma, False)[0]
            label = f"{'on' if down else 'above'}(t{slot[0] + 1},h{slot[1] + 1})"
            add(phase, mi, q0, v0, q1, v1, traj, traj.duration, label, vp)

        q_prev: FloatArray = wp.q_home
        slot_prev: Slot | None = None
        pending_up: tuple[int, Slot] | None = None  # the retreat waiting for its exit speed
        for mi, m in enumerate(moves):
            src, dst = (m.from_tower, m.from_height), (m.to_tower, m.to_height)
            q_src, q_dst = wp.table[src[0], src[1], ABOVE], wp.table[dst[0], dst[1], ABOVE]
            s0, s1, traj = horizontal(q_prev, slot_prev, q_src, src)
            if pending_up is not None:
                vertical(Phase.RETREAT, pending_up[0], pending_up[1], s0, down=False)
            add(Phase.TRANSIT, mi, q_prev, self.via_state(slot_prev, s0, False)[0], q_src,
                self.via_state(src, s1, True)[0], traj, traj.duration, f"above(t{src[0] + 1},h{src[1] + 1})")
            vertical(Phase.DESCEND_PICK, mi, src, s1, down=True)
            q_on = wp.table[src[0], src[1], ON]
            add(Phase.GRASP_DWELL, mi, q_on, zero, q_on, zero, None, dwell, f"on(t{src[0] + 1},h{src[1] + 1})")
            c0, c1, traj = horizontal(q_src, src, q_dst, dst)
            vertical(Phase.LIFT, mi, src, c0, down=False)
            add(Phase.CARRY, mi, q_src, self.via_state(src, c0, False)[0], q_dst, self.via_state(dst, c1, True)[0],
                traj, traj.duration, f"above(t{dst[0] + 1},h{dst[1] + 1})")
            vertical(Phase.DESCEND_PLACE, mi, dst, c1, down=True)
            q_on = wp.table[dst[0], dst[1], ON]
            add(Phase.RELEASE_DWELL, mi, q_on, zero, q_on, zero, None, dwell, f"on(t{dst[0] + 1},h{dst[1] + 1})")
            pending_up = (mi, dst)
            q_prev, slot_prev = q_dst, dst
        s0, _, traj = horizontal(q_prev, slot_prev, wp.q_home, None)
        if pending_up is not None:
            vertical(Phase.RETREAT, pending_up[0], pending_up[1], s0, down=False)
        add(Phase.HOME, -1, q_prev, self.via_state(slot_prev, s0, False)[0], wp.q_home, zero, traj, traj.duration,
            "home")
        return segs


# ------------------------------------------------------------------------------------------------- sampling
#
# Sampling is vectorized over all samples of the plan at once (a per-sample Python loop over ``at_time`` cost
# ~25 ms per move). It reproduces Ruckig's ``Trajectory.at_time`` arithmetic: each DoF's profile is 7 constant-jerk
# phases (``Profile.t`` durations; ``p``, ``v``, ``a`` at each phase start, and after the end), the phase is found by
# upper_bound on the cumulative times ``t_sum`` and the state integrated from its start with ``ruckig::integrate``.
# Segments whose profiles carry a brake pre-profile (only for starts outside the limits, which the planner never
# produces) take the per-sample ``at_time`` path instead.

_N_PIECES = 8  # pieces of a profile: 7 constant-jerk phases and the state after the end
# Samples per block of the elementwise evaluation. Arrays are joint-major (6, N), so broadcasting a per-sample (N,)
# operand runs numpy's inner loop over samples rather than over 6 joints; and blocks of 4096 keep every temporary
# (~200 kB) in cache and out of fresh-page allocation, ~3x faster than whole-plan temporaries.
_CHUNK = 4096


def _lexi_keys(group: npt.NDArray[np.intp], x: FloatArray) -> npt.NDArray[np.complex128]:
    """Keys that sort by (group, x) lexicographically: numpy orders complex numbers by real, then imaginary part.

    Used to run one exact ``searchsorted`` over many independently sorted runs (one run per group) at once.
    """
    return group.astype(float) + 1j * x


@dataclass(frozen=True)
class _ProfileTable:
    """Ruckig profiles of several trajectories, stacked as (trajectory row, DoF, piece) for vectorized evaluation.

    ``t_sum`` (R, D, 7): cumulative phase times (sequential sums, as Ruckig's own ``t_sum``, so the phase lookup
    matches it bit for bit); ``t0`` (R, D, 8): start time of each piece (0, then ``t_sum``); ``p, v, a, j``
    (R, D, 8): the state and jerk at each piece start. Piece 7 is "after the profile end" (constant acceleration,
    zero jerk), which Ruckig uses for a DoF that finishes early and at ``t = duration``.
    """

    t_sum: FloatArray
    t0: FloatArray
    p: FloatArray
    v: FloatArray
    a: FloatArray
    j: FloatArray

    @classmethod
    def of(cls, profiles: Sequence[Sequence[Any]]) -> _ProfileTable:
        """From ``profiles[r][d]`` (ruckig.Profile without brake), read once through the bindings as lists."""
        t = np.array([[prof.t for prof in row] for row in profiles], dtype=float).reshape(len(profiles), -1, 7)
        t_sum = np.cumsum(t, axis=2)  # add.accumulate: sequential, like Ruckig (not pairwise like np.sum)
        shape = (*t_sum.shape[:2], _N_PIECES)
        t0 = np.zeros(shape)
        t0[:, :, 1:] = t_sum
        p, v, a = (np.array([[getattr(prof, name) for prof in row] for row in profiles], dtype=float).reshape(shape)
                   for name in ("p", "v", "a"))
        j = np.zeros(shape)
        j[:, :, :7] = np.array([[prof.j for prof in row] for row in profiles], dtype=float).reshape((*shape[:2], 7))
        return cls(t_sum, t0, p, v, a, j)

    def evaluate(self, seg: npt.NDArray[np.intp], row_of_seg: npt.NDArray[np.intp], tau: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(position, velocity, acceleration, jerk), each (D, N) (DoF-major), at local times ``tau`` (N,).

        ``seg`` (N,) is the sample's segment index, non-decreasing, with ``tau`` non-decreasing within a segment;
        ``row_of_seg`` maps a segment index to its table row (-1: not evaluated here).
        """
        D = self.p.shape[1]
        n = len(tau)
        segs = np.flatnonzero(row_of_seg >= 0)  # every segment of this table, sampled or not
        rows = row_of_seg[segs]
        # Phase lookup for all samples and DoFs: first sample at or after each (segment, phase end) by one
        # searchsorted on (segment, tau) keys; a sample's phase index is then the number of its segment's phase ends
        # at or before it (upper_bound, as Ruckig), i.e. a running count minus the 7 ends of every earlier segment.
        pos = np.searchsorted(_lexi_keys(seg, tau), _lexi_keys(np.repeat(segs, D * 7), self.t_sum[rows].ravel()),
                              side="left")
        # Each DoF counts into its own lane of n + 1 slots (pos is ordered segment, DoF, phase end).
        lanes = (np.arange(D)[:, None] * (n + 1) + pos.reshape(len(segs), D, 7)).ravel()
        marks = np.bincount(lanes, minlength=D * (n + 1)).reshape(D, n + 1)
        earlier = np.cumsum(row_of_seg >= 0) - 1  # rank of each segment among this table's segments
        piece = np.cumsum(marks[:, :n], axis=1) - 7 * earlier[seg]
        flat = (row_of_seg[seg] * D + np.arange(D)[:, None]) * _N_PIECES + piece
        out = np.empty((4, D, n))
        t0, p, v, a, j = (x.ravel() for x in (self.t0, self.p, self.v, self.a, self.j))
        for c in range(0, n, _CHUNK):
            f, tc = flat[:, c:c + _CHUNK], tau[c:c + _CHUNK]
            dt = tc - t0.take(f)  # ndarray.take: a faster gather than fancy indexing
            p0, v0, a0, jj = p.take(f), v.take(f), a.take(f), j.take(f)
            # ruckig::integrate, same operation order.
            out[0, :, c:c + _CHUNK] = p0 + dt * (v0 + dt * (a0 / 2 + dt * jj / 6))
            out[1, :, c:c + _CHUNK] = v0 + dt * (a0 + dt * jj / 2)
            out[2, :, c:c + _CHUNK] = a0 + dt * jj
            out[3, :, c:c + _CHUNK] = jj
        return out[0], out[1], out[2], out[3]


def _profile_jerk(traj: RuckigTrajectory, tau: FloatArray) -> FloatArray:
    """Jerk of a Ruckig trajectory at local times ``tau`` (N,), read from its own per-DoF profiles: (N, dofs)."""
    profiles = traj.profiles[0]
    out = np.zeros((len(tau), len(profiles)))
    for i, prof in enumerate(profiles):
        tb = float(prof.brake.duration)
        t_bounds = tb + np.cumsum(prof.t)
        idx = np.searchsorted(t_bounds, tau, side="right")
        jerks = np.append(np.asarray(prof.j, dtype=float), 0.0)  # after the end: constant velocity
        out[:, i] = jerks[np.minimum(idx, 7)]
        if tb > 0.0:  # a brake pre-profile
            bb = np.cumsum(prof.brake.t)
            in_brake = tau < tb
            bidx = np.minimum(np.searchsorted(bb, tau[in_brake], side="right"), 1)
            out[in_brake, i] = np.asarray(prof.brake.j, dtype=float)[bidx]
    return out


def _at_times(traj: RuckigTrajectory, tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per-sample ``at_time`` (the fallback for profiles with a brake pre-profile): four (N, dofs) arrays."""
    states = np.array([traj.at_time(float(tt)) for tt in tau], dtype=float).reshape(len(tau), 3, -1)
    return states[:, 0], states[:, 1], states[:, 2], _profile_jerk(traj, tau)


class _StackedPaths:
    """The nodes of several :class:`VerticalPath` stacked (joint-major), to evaluate many paths in one call."""

    def __init__(self, paths: Sequence[VerticalPath]) -> None:
        self.sizes = np.array([len(vp.s) for vp in paths])
        self.first = np.cumsum(self.sizes) - self.sizes  # index of each path's first node
        self.s = np.concatenate([vp.s for vp in paths])
        self.q, self.dq, self.ddq, self.dddq = (np.concatenate([getattr(vp, name) for vp in paths]).T.copy()
                                                for name in ("q", "dq", "ddq", "dddq"))
        self.length = np.array([vp.length_m for vp in paths])
        self.node_keys = _lexi_keys(np.repeat(np.arange(len(paths)), self.sizes), self.s)

    def evaluate(self, which: npt.NDArray[np.intp], s: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`VerticalPath.evaluate` of path ``which[i]`` at ``s[i]`` (same arithmetic): four (6, N) arrays.

        One searchsorted on (path, s) keys finds each sample's node interval in its own path.
        """
        S = self.s
        s = np.minimum(np.maximum(s, 0.0), self.length[which])
        k = np.minimum(np.searchsorted(self.node_keys, _lexi_keys(which, s), side="right") - 1,
                       self.first[which] + self.sizes[which] - 2)
        k1 = k + 1
        h = S.take(k1) - S.take(k)
        u = (s - S.take(k)) / h
        # ndarray.take(axis=1): ~2x faster than fancy indexing [:, k] for these gathers.
        q0, q1, m0, m1 = self.q.take(k, 1), self.q.take(k1, 1), self.dq.take(k, 1) * h, self.dq.take(k1, 1) * h
        u2, u3 = u * u, u * u * u
        q = (2 * u3 - 3 * u2 + 1) * q0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * q1 + (u3 - u2) * m1
        dq = ((6 * u2 - 6 * u) * q0 + (3 * u2 - 4 * u + 1) * m0 + (-6 * u2 + 6 * u) * q1 + (3 * u2 - 2 * u) * m1) / h
        ddq = (1 - u) * self.ddq.take(k, 1) + u * self.ddq.take(k1, 1)
        dddq = (1 - u) * self.dddq.take(k, 1) + u * self.dddq.take(k1, 1)
        return q, dq, ddq, dddq


# Stacked nodes per set of paths (by identity; the entry holds the paths, so their ids are not reused while cached).
# The paths come from the per-station waypoint cache, so repeated plans on a station reuse the same stacks.
_STACKED_CACHE: dict[tuple[int, ...], tuple[tuple[VerticalPath, ...], _StackedPaths]] = {}


def _stacked_paths(paths: Sequence[VerticalPath]) -> _StackedPaths:
    key = tuple(id(vp) for vp in paths)
    hit = _STACKED_CACHE.get(key)
    if hit is None:
        if len(_STACKED_CACHE) >= 64:
            _STACKED_CACHE.clear()
        hit = _STACKED_CACHE[key] = (tuple(paths), _StackedPaths(paths))
    return hit[1]


def sample(segments: Sequence[Segment], rate_hz: float) -> Trajectory:
    """Uniform samples ``t = i / rate_hz`` of the chained segments, with suction, move index and phase.

    Joint segments: q, qd, qdd, qddd from the Ruckig profiles. Vertical legs: s, sd, sdd, sddd from the path
    trajectory's profile, mapped to joints by the chain rule. Both are evaluated for all samples at once (see the
    section comment); the per-segment Python work is reading each distinct Ruckig trajectory's profiles once.
    """
    duration = segments[-1].t_end
    n = math.ceil(duration * rate_hz - 1e-9) + 1
    t = np.arange(n) / rate_hz
    n_seg = len(segments)
    starts = np.array([s.t_start for s in segments])
    durations = np.array([s.duration for s in segments])
    # searchsorted <= n_seg, so only the lower bound needs clamping (np.clip has a much larger fixed cost).
    seg_of = np.maximum(np.searchsorted(starts, t, side="right") - 1, 0)
    tau = np.minimum(t - starts[seg_of], durations[seg_of])
    seg_phase = np.array([int(s.phase) for s in segments], dtype=int)
    phase = seg_phase[seg_of]
    mi = np.array([s.move_index for s in segments], dtype=int)[seg_of]

    # Table rows per segment (-1: none). The builder reuses one Ruckig trajectory for repeated legs, so each
    # distinct trajectory (by identity) is read from the bindings once.
    rows: tuple[dict[int, int], dict[int, int]] = ({}, {})  # joint, path: id(trajectory) -> row
    profiles: tuple[list[Any], list[Any]] = ([], [])
    row_of_seg = np.full((2, n_seg), -1, dtype=np.intp)
    path_rows: dict[int, int] = {}
    path_list: list[VerticalPath] = []
    path_of_seg = np.zeros(n_seg, dtype=np.intp)
    dwell_q = np.zeros((N_JOINTS, n_seg))
    slow: list[int] = []  # segments with a brake pre-profile: per-sample at_time
    for k, seg in enumerate(segments):
        traj = seg.trajectory
        if traj is None:
            dwell_q[:, k] = seg.q_start
            continue
        kind = 0 if seg.path is None else 1
        r = rows[kind].get(id(traj))
        if r is None:
            profs = traj.profiles[0]
            if any(prof.brake.duration > 0.0 for prof in profs):
                slow.append(k)
                continue
            r = rows[kind][id(traj)] = len(profiles[kind])
            profiles[kind].append(profs)
        row_of_seg[kind, k] = r
        if seg.path is not None:
            path_of_seg[k] = path_rows.setdefault(id(seg.path), len(path_list))
            if path_of_seg[k] == len(path_list):
                path_list.append(seg.path)

    # Joint-major (6, N) work arrays (see _ProfileTable.evaluate), transposed to the contract's (N, 6) at the end.
    q = dwell_q[:, seg_of]  # the dwells' rest pose; moving samples are overwritten below
    qd, qdd, qddd = np.zeros((N_JOINTS, n)), np.zeros((N_JOINTS, n)), np.zeros((N_JOINTS, n))
    idx = np.flatnonzero(row_of_seg[0, seg_of] >= 0)
    if idx.size:
        q[:, idx], qd[:, idx], qdd[:, idx], qddd[:, idx] = _ProfileTable.of(profiles[0]).evaluate(
            seg_of[idx], row_of_seg[0], tau[idx])
    idx = np.flatnonzero(row_of_seg[1, seg_of] >= 0)
    if idx.size:
        s_all = _ProfileTable.of(profiles[1]).evaluate(seg_of[idx], row_of_seg[1], tau[idx])
        stacked = _stacked_paths(path_list)
        which = path_of_seg[seg_of[idx]]
        for c in range(0, len(idx), _CHUNK):
            ii, cc = idx[c:c + _CHUNK], slice(c, c + _CHUNK)
            s, sd, sdd, sddd = (x[0, cc] for x in s_all)
            q[:, ii], d1, d2, d3 = stacked.evaluate(which[cc], s)
            qd[:, ii] = d1 * sd
            qdd[:, ii] = d2 * sd * sd + d1 * sdd
            qddd[:, ii] = d3 * sd**3 + 3 * d2 * sd * sdd + d1 * sddd
    for k in slow:
        seg = segments[k]
        assert seg.trajectory is not None
        i0, i1 = np.searchsorted(seg_of, [k, k + 1])
        x, xd, xdd, xddd = _at_times(seg.trajectory, tau[i0:i1])
        if seg.path is None:
            q[:, i0:i1], qd[:, i0:i1], qdd[:, i0:i1], qddd[:, i0:i1] = x.T, xd.T, xdd.T, xddd.T
        else:
            x, xd, xdd, xddd = x[:, 0], xd[:, 0], xdd[:, 0], xddd[:, 0]
            q[:, i0:i1], d1, d2, d3 = (y.T for y in seg.path.evaluate_many(x))
            qd[:, i0:i1] = d1 * xd
            qdd[:, i0:i1] = d2 * xd * xd + d1 * xdd
            qddd[:, i0:i1] = d3 * xd**3 + 3 * d2 * xd * xdd + d1 * xddd
    # Samples after the end (the last one) hold the final state at rest.
    last = t > duration
    qd[:, last], qdd[:, last], qddd[:, last] = 0.0, 0.0, 0.0
    # Per segment then gathered (np.isin has a large fixed cost, ~0.1 ms, against a few us for this).
    suction = np.array([seg.phase in SUCTION_PHASES for seg in segments], dtype=bool)[seg_of]
    q, qd, qdd, qddd = (np.ascontiguousarray(x.T) for x in (q, qd, qdd, qddd))
    return Trajectory(rate_hz=float(rate_hz), t=t, q=q, qd=qd, qdd=qdd, qddd=qddd, suction=suction,
                      move_index=mi, phase=phase)


# --------------------------------------------------------------------------------------------------- checks


def check_limits(tr: Trajectory, segments: Sequence[Segment], limits: KinematicLimits,
                 q_min: Sequence[float], q_max: Sequence[float]) -> list[str]:
    """Joint position (between samples too: Ruckig's position extrema, or the vertical path's nodes), velocity,
    acceleration and jerk limits at every sample (relative tolerance LIMIT_RTOL)."""
    out: list[str] = []
    lo, hi = np.asarray(q_min), np.asarray(q_max)
    for seg in segments:
        if seg.trajectory is None:
            continue
        if seg.path is not None:
            mins, maxs = seg.path.q.min(axis=0), seg.path.q.max(axis=0)
        else:
            mins = np.array([e.min for e in seg.trajectory.position_extrema])
            maxs = np.array([e.max for e in seg.trajectory.position_extrema])
        bad = np.flatnonzero((mins < lo - POSITION_ATOL) | (maxs > hi + POSITION_ATOL))
        for i in bad:
            out.append(f"joint {i + 1} position [{mins[i]:.4f}, {maxs[i]:.4f}] rad leaves [{lo[i]:.4f}, "
                       f"{hi[i]:.4f}] in {seg.phase.name} (move {seg.move_index + 1})")
    bad_q = (tr.q < lo - POSITION_ATOL) | (tr.q > hi + POSITION_ATOL)
    if np.any(bad_q):
        k, i = np.argwhere(bad_q)[0]
        out.append(f"joint {i + 1} position {tr.q[k, i]:.4f} rad outside limits at t = {tr.t[k]:.3f} s")
    for name, arr, lim in (("velocity", tr.qd, limits.v_max), ("acceleration", tr.qdd, limits.a_max),
                           ("jerk", tr.qddd, limits.j_max)):
        ratio = np.abs(arr) / lim
        if np.any(ratio > 1.0 + LIMIT_RTOL):
            k, i = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
            out.append(f"joint {i + 1} {name} {arr[k, i]:.6g} exceeds the limit {lim[i]:.6g} at t = "
                       f"{tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name})")
    return out


def _tcp_positions_world(station: Station, q: FloatArray) -> FloatArray:
    """World position [m] of the suction point at every row of ``q`` (N, 6): batched UR3 DH forward kinematics.

    Same kinematics as ``Ur3Model.fk(q, "tcp")`` (the URDF and the DH table agree to ~1e-11 m), without a
    per-sample Pinocchio call.
    """
    T = dh_fk(q)
    t_flange_tcp = load_ur3(station.tool, station.limits).T_flange_tcp("tool0").translation
    p_base = T[:, :3, :3] @ t_flange_tcp + T[:, :3, 3]
    T_wb = station.T_world_base
    return p_base @ T_wb.rotation.T + T_wb.translation


def check_vertical(tr: Trajectory, moves: Sequence[Move], station: Station, tol_m: float) -> tuple[list[str], float]:
    """FK at every sample of the vertical phases: suction point within ``tol_m`` of the block's vertical line.

    Returns (violations, worst deviation [m]).
    """
    out: list[str] = []
    vert = np.flatnonzero(np.isin(tr.phase, [int(p) for p in VERTICAL_PHASES]))
    if vert.size == 0:
        return out, 0.0
    # The slot of every vertical sample: the move's source while picking/lifting, else its destination.
    src = np.array([(m.from_tower, m.from_height) for m in moves], dtype=int).reshape(-1, 2)
    dst = np.array([(m.to_tower, m.to_height) for m in moves], dtype=int).reshape(-1, 2)
    mi = tr.move_index[vert]
    at_src = np.isin(tr.phase[vert], [int(Phase.DESCEND_PICK), int(Phase.LIFT)])
    slot = np.where(at_src[:, None], src[mi], dst[mi])
    line_xy = np.array([[contact_point_world(station, t, h)[:2] for h in range(station.n_heights)]
                        for t in range(station.n_towers)])
    p = _tcp_positions_world(station, tr.q[vert])
    dev = np.linalg.norm(p[:, :2] - line_xy[slot[:, 0], slot[:, 1]], axis=1)
    for i in np.flatnonzero(dev > tol_m)[:5]:
        k, (tower, height) = vert[i], slot[i]
        out.append(f"suction point {dev[i] * 1e3:.2f} mm off the vertical line of tower {tower + 1} height "
                   f"{height + 1} at t = {tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name}, move "
                   f"{tr.move_index[k] + 1}); allowed {tol_m * 1e3:.1f} mm")
    return out, float(np.max(dev))


class CollisionScene:
    """Pinocchio GeometryModel of the UR3's URDF collision meshes plus coal boxes: the table, the resting blocks,
    the carried block (attached to the suction point) and a small suction cup at the TCP.

    Distances come from ``pin.computeDistance`` (coal); the robot's meshes are replaced by their convex hulls
    (conservative, much faster). Required distances: robot geometry and carried block
    above the table (> 0), robot geometry clear of resting blocks (> 0), carried block >= ``clearance_m`` from
    every other block. Pairs excluded, and why:

    - base_link vs table: the robot is mounted on the table.
    - cup vs the block being picked (descend/grasp) or just placed (release/retreat): contact by design.
    - carried block vs the block under it (stacked layout) during lift / descend-place, and vs the table during
      lift / descend-place: the block rests on them at contact.
    - cup vs table during the vertical and dwell phases: the cup is at contact there.

    Decimation (proof sketch): every point of the robot and of the carried block moves at most
    ``sum_i |qd_i| R_i`` [m/s], with ``R_i`` a bound on the distance from joint i's origin to any geometry
    downstream of it (sum of the following joint offsets plus the geometry's offset and bounding radius). Over a
    coarse interval [t_a, t_b] no point is farther than ``delta = sum_i max|qd_i| R_i (t_b - t_a) / 2`` from its
    position at the nearer end (max over the interval's samples plus a_max times half a sample step), and a
    distance between two bodies changes at most by the displacement of their points. A pair whose distance
    exceeds ``required + delta`` at both ends is therefore fine at every sample in between; otherwise every
    sample of the interval is checked.
    """

    CUP_RADIUS_M = 0.01
    CUP_LENGTH_M = 0.02

    def __init__(self, station: Station, n_blocks: int) -> None:
        import coal

        self.station = station
        robot = load_ur3(station.tool, station.limits)
        self.robot = robot
        self.model = robot.model
        self.data = self.model.createData()
        gm = pin.buildGeomFromUrdfString(self.model, robot.urdf, pin.COLLISION)
        for g in gm.geometryObjects:
            # Convex hulls of the URDF meshes: ~30x faster GJK distances than the triangle BVHs, and a superset of
            # each mesh, so a distance can only be under-estimated (the check stays conservative).
            if isinstance(g.geometry, coal.BVHModelBase):
                g.geometry.buildConvexRepresentation(False)
                g.geometry = g.geometry.convex
        self.robot_geoms = list(range(len(gm.geometryObjects)))
        names = [g.name for g in gm.geometryObjects]
        self.base_geom = names.index("base_link_0") if "base_link_0" in names else -1
        T_baselink_world = T_BASELINK_BASE * station.T_world_base.inverse()
        self.T_baselink_world = T_baselink_world
        fid = robot.frame_ids["tcp"]
        frame = self.model.frames[fid]
        joint6 = frame.parentJoint
        T_j6_tcp = frame.placement
        # Suction cup: a short cylinder above the suction point (tcp z points into the block).
        cup = pin.GeometryObject("cup", joint6, fid, T_j6_tcp * pin.SE3(np.eye(3), np.array(
            [0.0, 0.0, -0.5 * self.CUP_LENGTH_M])), coal.Cylinder(self.CUP_RADIUS_M, self.CUP_LENGTH_M))
        self.cup = gm.addGeometryObject(cup)
        s = station.block_size
        # Block centre seen from the TCP: contact_depth - s/2 above it, i.e. along tcp -z.
        T_tcp_block = pin.SE3(np.eye(3), np.array([0.0, 0.0, -(station.contact_depth - 0.5 * s)]))
        self.carried = gm.addGeometryObject(pin.GeometryObject("carried_block", joint6, fid, T_j6_tcp * T_tcp_block,
                                                               coal.Box(s, s, s)))
        tz = table_z(station)
        table = pin.GeometryObject("table", 0, 0, T_baselink_world * pin.SE3(np.eye(3), np.array(
            [0.0, 0.0, tz - 0.05])), coal.Box(4.0, 4.0, 0.1))
        self.table = gm.addGeometryObject(table)
        self.blocks = []
        for b in range(n_blocks):
            self.blocks.append(gm.addGeometryObject(pin.GeometryObject(f"block_{b}", 0, 0, pin.SE3.Identity(),
                                                                       coal.Box(s, s, s))))
        self.gm = gm
        self.pairs: dict[tuple[int, int], int] = {}
        movers = [*self.robot_geoms, self.cup, self.carried]
        for a in movers:
            for b in [self.table, *self.blocks]:
                self.pairs[(a, b)] = len(self.pairs)
                gm.addCollisionPair(pin.CollisionPair(a, b))
        self.gd = pin.GeometryData(gm)
        self.R = self._reach_bounds()
        self._R_block = R_world_tcp_down(station.tool_yaw)

    def _reach_bounds(self) -> FloatArray:
        """R_i [m]: bound on the distance from joint i's origin to any geometry attached at or after joint i."""
        m = self.model
        offs = [float(np.linalg.norm(m.jointPlacements[j].translation)) for j in range(m.njoints)]
        R = np.zeros(N_JOINTS)
        for i in range(1, N_JOINTS + 1):
            chain = sum(offs[i + 1:])
            extent = 0.0
            for g in self.gm.geometryObjects:
                if g.parentJoint >= i:
                    g.geometry.computeLocalAABB()
                    ext = (float(np.linalg.norm(g.placement.translation))
                           + float(np.linalg.norm(g.geometry.aabb_center)) + float(g.geometry.aabb_radius))
                    extent = max(extent, ext)
            R[i - 1] = chain + extent
        return R

    def place_blocks(self, slots: dict[int, tuple[int, int]]) -> None:
        """Put each resting block (block -> (tower, height)) at its slot; blocks not listed are parked far away."""
        for b, gid in enumerate(self.blocks):
            p = block_center_world(self.station, *slots[b]) if b in slots else np.array([100.0 + 10 * b, 100.0, 100.0])
            self.gm.geometryObjects[gid].placement = self.T_baselink_world * pin.SE3(self._R_block, p)

    def distances(self, q: FloatArray, pairs: Sequence[tuple[int, int]]) -> FloatArray:
        pin.updateGeometryPlacements(self.model, self.data, self.gm, self.gd, q)
        return np.array([pin.computeDistance(self.gm, self.gd, self.pairs[p]).min_distance for p in pairs])

    def name(self, gid: int) -> str:
        return self.gm.geometryObjects[gid].name


@lru_cache(maxsize=8)
def _collision_scene(station: Station, n_blocks: int) -> CollisionScene:
    """The scene of a station and block count, built once: reading and hulling the URDF meshes (~0.2 s) is most of
    a clearance check otherwise. Shared like ``load_ur3``'s models, so not thread-safe either."""
    return CollisionScene(station, n_blocks)


def check_collisions(tr: Trajectory, moves: Sequence[Move], station: Station, n_blocks: int, start: int,
                     config: PlanConfig, limits: KinematicLimits) -> list[str]:
    """Clearance checks of :class:`CollisionScene` on the sampled trajectory (decimated with a proven margin)."""
    scene = _collision_scene(station, n_blocks)
    # Fresh GeometryData: Pinocchio warm-starts GJK from each pair's previous query (enable_cached_gjk_guess), so
    # reusing it would let the distances depend, in the last bits, on the plans checked before. Block placements
    # need no reset: every run below places all blocks before its first query.
    scene.gd = pin.GeometryData(scene.gm)
    stacks = stacks_before_moves(moves, n_blocks, start, station.n_towers)
    out: list[str] = []
    dt = 1.0 / tr.rate_hz
    stride = max(1, round(tr.rate_hz / config.collision_rate_hz))
    speed_bound = np.abs(tr.qd) + limits.a_max * dt / 2  # bound between samples
    # Segments of constant (move, phase): the active pairs are fixed within each.
    change = np.flatnonzero((np.diff(tr.phase) != 0) | (np.diff(tr.move_index) != 0)) + 1
    runs = np.split(np.arange(len(tr.t)), change)
    for run in runs:
        mi, ph = int(tr.move_index[run[0]]), Phase(int(tr.phase[run[0]]))
        state = stacks[mi] if mi >= 0 else (stacks[-1] if ph == Phase.HOME else stacks[0])
        m = moves[mi] if mi >= 0 else None
        slots = {b: (t, h) for t, st in enumerate(state) for h, b in enumerate(st)}
        after_place = m is not None and ph in (Phase.RELEASE_DWELL, Phase.RETREAT)
        if after_place:
            assert m is not None
            slots.pop(m.block, None)
            slots[m.block] = (m.to_tower, m.to_height)
        carrying = m is not None and ph.carrying
        if carrying:
            assert m is not None
            slots.pop(m.block, None)
        scene.place_blocks(slots)
        pairs: list[tuple[tuple[int, int], float]] = []
        for g in [*scene.robot_geoms, scene.cup]:
            if g == scene.base_geom:
                continue
            if not (g == scene.cup and ph in (*VERTICAL_PHASES, *DWELL_PHASES)):
                pairs.append(((g, scene.table), 0.0))
            for b in slots:
                if g == scene.cup and m is not None and b == m.block and ph in (
                        Phase.DESCEND_PICK, Phase.GRASP_DWELL, Phase.RELEASE_DWELL, Phase.RETREAT):
                    continue
                pairs.append(((g, scene.blocks[b]), 0.0))
        if carrying:
            assert m is not None
            if ph == Phase.CARRY:
                pairs.append(((scene.carried, scene.table), 0.0))
            under = None
            if station.layout == "stacked":
                if ph == Phase.LIFT and m.from_height > 0:
                    under = (m.from_tower, m.from_height - 1)
                if ph == Phase.DESCEND_PLACE and m.to_height > 0:
                    under = (m.to_tower, m.to_height - 1)
            for b, slot in slots.items():
                if slot != under:
                    pairs.append(((scene.carried, scene.blocks[b]), config.clearance_m))
        if not pairs:
            continue
        keys = [p for p, _ in pairs]
        req = np.array([r for _, r in pairs])
        coarse = list(run[::stride])
        if coarse[-1] != run[-1]:
            coarse.append(run[-1])
        d_coarse = {k: scene.distances(tr.q[k], keys) for k in coarse}
        checked: dict[int, FloatArray] = dict(d_coarse)
        for a, b in itertools.pairwise(coarse):
            vmax = np.max(speed_bound[a:b + 1], axis=0)
            delta = float(np.sum(vmax * scene.R)) * (tr.t[b] - tr.t[a]) / 2
            if np.any(np.minimum(d_coarse[a], d_coarse[b]) - req < delta):
                for k in range(a + 1, b):
                    checked[k] = scene.distances(tr.q[k], keys)
        for k in sorted(checked):
            bad = np.flatnonzero(checked[k] < req + (req == 0) * 1e-9)
            for j in bad:
                g1, g2 = keys[j]
                out.append(f"{scene.name(g1)} is {checked[k][j] * 1e3:.2f} mm from {scene.name(g2)} (required "
                           f"{req[j] * 1e3:.1f} mm) at t = {tr.t[k]:.3f} s ({ph.name}, move {mi + 1})")
                break
            if len(out) >= 5:
                return out
    return out


# ------------------------------------------------------------------------------------------------ public API


def plan_moves(station: Station, moves: Sequence[Move], config: PlanConfig | None = None, *, start: int = 0,
               end: int = 1, n_blocks: int | None = None) -> Plan:
    """Time-parameterize a given (legal) move sequence on ``station``; see :func:`plan_solve`."""
    config = config or PlanConfig()
    config.validate()
    n_blocks = n_blocks if n_blocks is not None else (max(m.block for m in moves) + 1 if moves else 0)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    wp = build_waypoints(station)
    timings["waypoints"] = time.perf_counter() - t0
    builder = _Builder(station, wp, config)
    limits = builder.limits
    t0 = time.perf_counter()
    segments = builder.build(moves)
    timings["build"] = time.perf_counter() - t0
    timings["ruckig"] = builder.ruckig_seconds
    # Stop-and-go reference: the same waypoints and limits, zero velocity at every waypoint.
    t0 = time.perf_counter()
    stop_go = _Builder(station, wp, config, pass_through=False).build(moves)[-1].t_end
    timings["stop_and_go"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = sample(segments, config.rate_hz)
    timings["sampling"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    violations = check_limits(tr, segments, limits, station.limits.q_min, station.limits.q_max)
    vert, _ = check_vertical(tr, moves, station, config.vertical_tol_m)
    violations += vert
    timings["checks"] = time.perf_counter() - t0
    if config.check_collisions and moves:
        t0 = time.perf_counter()
        violations += check_collisions(tr, moves, station, n_blocks, start, config, limits)
        timings["collision"] = time.perf_counter() - t0
    duration = segments[-1].t_end
    dwell_total = 2 * len(moves) * config.dwell_s
    plan = Plan(station=station, moves=tuple(moves), trajectory=tr, stop_and_go_duration_s=stop_go, config=config,
                segments=tuple(segments), limits=limits, violations=tuple(violations), duration_s=duration,
                dwell_total_s=dwell_total, stop_and_go_motion_s=stop_go - dwell_total, start=start, end=end,
                n_blocks=n_blocks, timings_s=timings)
    if violations and config.raise_on_violation:
        more = f" (+{len(violations) - 1} more)" if len(violations) > 1 else ""
        raise PlanError(f"plan on {station.name} violates a safety check: {violations[0]}{more}")
    return plan


def plan_solve(station: Station, start: int, end: int, n_blocks: int, config: PlanConfig | None = None) -> Plan:
    """Solve the Hanoi instance (0-based towers) and time-parameterize the whole motion with Ruckig.

    Raises:
        PuzzleError: invalid instance (start == end, tower outside the grid, too many blocks).
        PlanError: Ruckig failure or a safety check violation (limits, vertical approach, clearance).
        IKError: a waypoint is unreachable on the home branch.
    """
    moves = solve_hanoi(n_blocks, start, end, station.n_towers, station.n_heights)
    check_sequence(moves, n_blocks, start, end, station.n_towers, station.n_heights)
    return plan_moves(station, moves, config, start=start, end=end, n_blocks=n_blocks)


def trajectory_csv(tr: Trajectory) -> str:
    """CSV text: header ``t,q1..q6,qd1..qd6,suction``; t [s], q [rad], qd [rad/s], suction 0/1."""
    header = ",".join(["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction"])
    lines = [header]
    for k in range(len(tr.t)):
        vals = [f"{tr.t[k]:.6f}", *(repr(float(x)) for x in tr.q[k]), *(repr(float(x)) for x in tr.qd[k]),
                "1" if tr.suction[k] else "0"]
        lines.append(",".join(vals))
    return "\n".join(lines) + "\n"


__all__ = [
    "DEFAULT_VIA_FRACTIONS",
    "CollisionScene",
    "KinematicLimits",
    "Phase",
    "Plan",
    "PlanConfig",
    "Segment",
    "Trajectory",
    "VerticalPath",
    "Waypoints",
    "build_waypoints",
    "check_collisions",
    "check_limits",
    "check_vertical",
    "plan_moves",
    "plan_solve",
    "sample",
    "trajectory_csv",
]
