"""The data types of a motion plan: phases, the sampled trajectory, limits, settings, segments and the plan.

All are frozen dataclasses (or an IntEnum); the modules of :mod:`ur3hanoi.plan` create and read them.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from enum import IntEnum
from functools import cached_property

import numpy as np
import numpy.typing as npt
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.hanoi import Move
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station

# The via grid at the above poses (see ur3hanoi.plan.motion.legs): path speeds in units of vb = L / T0 and path
# accelerations in units of vb / T0 (L: approach length, T0: the slot's joint-space rest-to-rest leg). The lab
# stations' optima lie at 1.25-2.5 vb and 1-4 vb / T0; 0 must be in both (the rest-to-rest fallback).
DEFAULT_VIA_SPEEDS: tuple[float, ...] = (0.0, 0.5, 1.0, 1.25, 1.5, 1.75, 2.0, 2.25, 2.5, 3.0)
DEFAULT_VIA_ACCELS: tuple[float, ...] = (-2.0, 0.0, 1.0, 2.0, 3.0, 4.0, 6.0)

# [m/s^2] What the suction holds while carrying, as |a - g| of the suction point: a quarter of what the simulated
# seal holds. bench/bench_suction_hold.py measures, over every carrying control cycle of the lab solves in MuJoCo,
# at most 0.0030 mm of suction-weld stretch per m/s^2 of |a - g| (the 0.004 s weld of ur3hanoi.sim.SceneConfig); the
# seal counts as broken at 10 mm of stretch (ur3hanoi.sim.SuctionConfig.hold_tolerance), i.e. at about 3300 m/s^2.
# The lab plans need at most about 12.8 m/s^2.
SUCTION_HOLD_MPS2 = 800.0


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
class KinematicLimits:
    """Per-joint limits used for planning [rad/s, rad/s^2, rad/s^3], already scaled by ``PlanConfig.speed``."""

    v_max: FloatArray
    a_max: FloatArray
    j_max: FloatArray


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
class Trajectory:
    """Sampled joint trajectory at ``rate_hz``.

    Samples are uniform, ``t[i] = i / rate_hz``; the last sample is the first one at or after the end of the
    motion, so it holds the final (home) state exactly.

    Attributes:
        t: (N,) sample times [s].
        q, qd, qdd, qddd: (N, 6) joint position, velocity, acceleration, jerk [rad, rad/s, rad/s^2, rad/s^3].
        suction: (N,) commanded suction.
        move_index: (N,) 0-based index into ``Plan.moves``; -1 before the first move and on the way home.
        phase: (N,) :class:`Phase` values.
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
class PlanConfig:
    """Planner settings. ``speed`` scales velocity, acceleration and jerk limits (0 < speed <= 1).

    Attributes:
        speed: scale of v_max, a_max and j_max (0 < speed <= 1).
        rate_hz: sample rate [Hz]; 125 (CB3) or 500 (e-Series), any positive rate is accepted.
        dwell_s: time at rest at each contact pose for the suction to build up / release [s].
        v_max, a_max, j_max: per-joint overrides [rad/s, rad/s^2, rad/s^3] (None: the station's JointLimits).
        pass_through: False plans stop-and-go (zero velocity at every waypoint).
        blend: start the motion across inside the vertical corridor (see :mod:`ur3hanoi.plan.motion.blend`).
        via_speeds, via_accels: the grid of via states at the above poses, in units of each slot's own rest-to-rest
            leg (see :mod:`ur3hanoi.plan.motion.legs`); both must contain 0.
        vertical_tol_m: allowed distance [m] of the suction point from the vertical line in vertical phases.
        clearance_m: required clearance [m] of the carried block from every other block.
        check_collisions: run the Pinocchio/coal clearance checks (slower; limits are always checked).
        collision_rate_hz: coarse rate [Hz] of the clearance check; refined down to 1 ms where the margin is not
            provably enough (see :mod:`ur3hanoi.plan.checks.clearance`).
        raise_on_violation: raise PlanError on the first violation list (False: return it in Plan.violations).
        suction_hold_mps2: the most the suction holds while carrying, as ``|a - g|`` of the suction point
            [m/s^2] (weight plus inertia per kg of block). Default :data:`SUCTION_HOLD_MPS2`, see there.
    """

    speed: float = 1.0
    rate_hz: float = 125.0
    dwell_s: float = 0.3
    v_max: tuple[float, ...] | None = None
    a_max: tuple[float, ...] | None = None
    j_max: tuple[float, ...] | None = None
    pass_through: bool = True
    blend: bool = True
    via_speeds: tuple[float, ...] = DEFAULT_VIA_SPEEDS
    via_accels: tuple[float, ...] = DEFAULT_VIA_ACCELS
    vertical_tol_m: float = 0.002
    clearance_m: float = 0.005
    check_collisions: bool = True
    collision_rate_hz: float = 25.0
    raise_on_violation: bool = True
    suction_hold_mps2: float = SUCTION_HOLD_MPS2

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
        for name in ("via_speeds", "via_accels"):
            grid = getattr(self, name)
            lo = 0.0 if name == "via_speeds" else -math.inf
            if (0.0 not in grid or not all(math.isfinite(x) and x >= lo for x in grid)
                    or any(b <= a for a, b in itertools.pairwise(grid))):
                raise PlanError(f"{name} = {grid!r} is invalid: expected increasing finite values including 0"
                                + (", none negative" if name == "via_speeds" else ""))
        for name in ("collision_rate_hz", "vertical_tol_m", "clearance_m", "suction_hold_mps2"):
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
    ``q_start``. Usually 6-DoF in joint space; for a vertical leg that follows the line exactly (the rest-to-rest
    fallback of :mod:`ur3hanoi.plan.motion.legs`) ``path`` is set and ``trajectory`` is the 1-DoF Ruckig trajectory
    of the path coordinate s [m] (see :class:`VerticalPath`). ``target`` names the
    waypoint reached at the segment's end (1-based tower/height): ``above``, ``on``, ``over`` (risen over taller
    towers), ``via`` (an interior point of a vertical leg) or ``home``.
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

    Attributes:
        station, moves, config: the station, the move sequence and the settings planned with.
        trajectory: the sampled motion.
        stop_and_go_duration_s: cycle time [s] of the honest baseline: joint-space Ruckig from rest to rest between
            the same waypoints under the same limits, with the same dwells (it ignores the vertical line; see
            :mod:`ur3hanoi.plan.baseline.stop_and_go`).
        segments: the chained Ruckig segments and dwells.
        limits: the planning limits actually used.
        violations: safety check failures (empty for a valid plan; non-empty only if not raise_on_violation).
        duration_s: exact cycle time [s] (the sampled trajectory ends on the first sample at or after it).
        dwell_total_s: time at rest in the grasp/release dwells [s].
        stop_and_go_motion_s: the honest baseline's cycle minus the same dwells [s].
        start, end, n_blocks: the instance (0-based towers).
        timings_s: wall-clock planning times [s]: "build" (connections, including their Ruckig calls; "ruckig" is
            that share), "baselines", "sampling", "checks", "collision".
        exact_vertical_stop_and_go_duration_s: cycle time [s] of stop-and-go with approach and retreat following
            the vertical line exactly (1-DoF path timing with constant limits), same dwells: the old reference.
        exact_vertical_stop_and_go_motion_s: the same minus the dwells [s].
        vertical_deviation_m: worst distance [m] of the suction point from the vertical line over the plan's
            approach and retreat legs, by forward kinematics at 1 kHz.
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
    exact_vertical_stop_and_go_duration_s: float = 0.0
    exact_vertical_stop_and_go_motion_s: float = 0.0
    vertical_deviation_m: float = 0.0

    @property
    def motion_s(self) -> float:
        """Cycle time minus the dwells [s]."""
        return self.duration_s - self.dwell_total_s

    @property
    def motion_saving(self) -> float:
        """Relative motion-time saving over the honest stop-and-go baseline (0.15 = 15 % faster)."""
        return 1.0 - self.motion_s / self.stop_and_go_motion_s if self.stop_and_go_motion_s > 0 else 0.0

