"""Connections between above points, and the per-station cache that plans them.

A connection is everything between two grasp/release dwells (or home): the exit leg of the slot it leaves
(lift or retreat), the joint-space Ruckig motion across to the slot it enters (through "over" points when towers on
the way are taller than the above poses), and that slot's entry leg (descend). Its via cells (the states at the two
above poses) are chosen by :func:`~ur3hanoi.plan.motion.via.best_cells` for the least summed duration; the legs come
from :class:`~ur3hanoi.plan.motion.legs.SlotLegs`; then :class:`~ur3hanoi.plan.motion.blend.Blender` starts the motion
across inside the corridor at both above poses. The over points are passed at rest (tall grids only: the lab's towers
never need them).

:func:`station_planner` returns the :class:`StationPlanner` of a station and its planning limits, built once and
cached (least recently used, a few stations): its legs, connections and reference durations are memoized. Every
entry is a pure function of its key, and the keys hold the whole calibration geometry (the :class:`Station` value,
compared field by field, without its name and file) and the limits, so a changed calibration can never reuse a
stale entry, and the results do not depend on what was planned before.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.plan.motion.blend import Blender, lateral_direction
from ur3hanoi.plan.motion.corridor import Cell, Leg, State, within_limits
from ur3hanoi.plan.motion.legs import SlotLegs
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.motion.vertical import PathLimits, line_ik
from ur3hanoi.plan.motion.via import Pair, best_cells
from ur3hanoi.plan.motion.waypoints import Waypoints, build_waypoints, geometry_key
from ur3hanoi.plan.types import KinematicLimits
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, contact_point_world

Slot = tuple[int, int]  # (tower, height), 0-based
ConnectionKey = tuple[Slot | None, Slot | None, float | None, float | None]  # slot0, slot1, over0, over1

# Start of the via search, in the grid's units (vb, vb / T0): near the optimum of the lab stations' connections.
SEARCH_START = (2.0, 1.0)


@dataclass(frozen=True)
class Connection:
    """From the dwell at ``slot0`` (None: home) to the dwell at ``slot1`` (None: home).

    Attributes:
        exit: the lift/retreat leg of ``slot0`` (None from home).
        across: the joint states from the exit above pose to the entry above pose (through any over points) and
            the Ruckig trajectories between them.
        entry: the descend leg of ``slot1`` (None to home).
        cells: the via cells at the two above poses (None at home).
    """

    exit: Leg | None
    across_states: tuple[State, ...]
    across: tuple[RuckigTrajectory, ...]
    entry: Leg | None
    cells: tuple[Cell | None, Cell | None]

    @property
    def duration(self) -> float:
        legs = sum(leg.duration for leg in (self.exit, self.entry) if leg is not None)
        return legs + sum(t.duration for t in self.across)


class StationPlanner:
    """Legs, connections and reference durations of one station under one set of limits (memoized).

    Args:
        station: the station.
        limits: the planning limits.
        tol_m: allowed distance [m] of the suction point from the vertical line on approach and retreat.
        via_speeds, via_accels: the via grid (see :mod:`ur3hanoi.plan.motion.legs`); ``pass_through`` False plans
            every via at rest.
        blend: add the lateral via accelerations of :mod:`ur3hanoi.plan.motion.blend` (pass-through only).
    """

    def __init__(self, station: Station, limits: KinematicLimits, tol_m: float, via_speeds: tuple[float, ...],
                 via_accels: tuple[float, ...], pass_through: bool = True, blend: bool = True) -> None:
        self.station = station
        self.blend = blend and pass_through
        self.limits = limits
        self.tol_m = tol_m
        self.wp: Waypoints = build_waypoints(station)
        self.ruckig = OfflineRuckig(limits.v_max, limits.a_max, limits.j_max)
        self.via_speeds = via_speeds if pass_through else (0.0,)
        self.via_accels = via_accels if pass_through else (0.0,)
        self._slots: dict[Slot, SlotLegs] = {}
        self._connections: dict[ConnectionKey, Connection] = {}
        self._over: dict[tuple[Slot, float], FloatArray] = {}
        self._rest: dict[tuple[bytes, bytes], float] = {}
        self._exact_leg: dict[Slot, float] = {}
        self._zero = np.zeros(N_JOINTS)

    @property
    def ruckig_seconds(self) -> float:
        """Wall-clock time spent in Ruckig calculations by this planner so far [s]."""
        return self.ruckig.seconds

    # ----------------------------------------------------------------------------------------------- poses

    def slot_legs(self, slot: Slot) -> SlotLegs:
        if slot not in self._slots:
            self._slots[slot] = SlotLegs(self.station, self.wp, slot, self.ruckig, self.limits, self.via_speeds,
                                         self.via_accels, self.tol_m)
        return self._slots[slot]

    def q_above(self, slot: Slot | None) -> FloatArray:
        return self.wp.q_home if slot is None else self.wp.table[slot[0], slot[1], ABOVE]

    def z_above(self, slot: Slot) -> float:
        """World height [m] of the suction point at the slot's above pose."""
        return float(contact_point_world(self.station, *slot)[2]) + self.station.approach

    def over_pose(self, slot: Slot, z: float) -> FloatArray:
        """Joints [rad] with the suction point on the slot's vertical line at world height ``z`` [m] (above the
        above pose), tool down, on home's branch: where a motion rises to clear taller towers."""
        key = (slot, z)
        if key not in self._over:
            st = self.station
            ik = line_ik(load_ur3(st.tool, st.limits, st.robot), st, *slot)
            try:
                self._over[key] = ik(self.z_above(slot) - z, self.q_above(slot))
            except PlanError as e:
                raise PlanError(f"tower {slot[0] + 1} height {slot[1] + 1}: no IK solution {z * 1e3:.1f} mm high "
                                "over it, where the motion must rise to clear the towers on its way (the grid is too "
                                "tall for the robot's reach)") from e
        return self._over[key]

    # ----------------------------------------------------------------------------------------------- connections

    def connect(self, slot0: Slot | None, slot1: Slot | None, over0: float | None = None,
                over1: float | None = None) -> Connection:
        """The best connection from the dwell at ``slot0`` to the dwell at ``slot1`` (None: home), rising to the
        world heights ``over0`` / ``over1`` [m] over the two slots on the way if given (memoized)."""
        key = (slot0, slot1, over0, over1)
        if key not in self._connections:
            self._connections[key] = self._connect(*key)
        return self._connections[key]

    def memoized(self, key: ConnectionKey) -> Connection | None:
        """The connection of ``key`` (slot0, slot1, over0, over1) if this planner has it already, else None."""
        return self._connections.get(key)

    def memoize(self, key: ConnectionKey, connection: Connection) -> None:
        """Keep a connection of ``key`` obtained elsewhere (:mod:`ur3hanoi.plan.route.stored`, the user's cache)."""
        self._connections[key] = connection

    def _connect(self, slot0: Slot | None, slot1: Slot | None, over0: float | None,
                 over1: float | None) -> Connection:
        legs0 = self.slot_legs(slot0) if slot0 is not None else None
        legs1 = self.slot_legs(slot1) if slot1 is not None else None
        z = self._zero
        middle: list[State] = []
        if over0 is not None and slot0 is not None:
            middle.append((self.over_pose(slot0, over0), z, z))
        if over1 is not None and slot1 is not None:
            middle.append((self.over_pose(slot1, over1), z, z))
        home: State = (self.wp.q_home, z, z)
        fixed = self.ruckig.chain(middle) if len(middle) > 1 else []
        if fixed is None:
            raise PlanError(f"Ruckig could not connect the over points of {slot0} and {slot1}")
        n0 = legs0.shape if legs0 is not None else (1, 1)
        n1 = legs1.shape if legs1 is not None else (1, 1)
        across_memo: dict[Pair, tuple[float, list[State], list[RuckigTrajectory] | None]] = {}

        def states_across(ix: Pair) -> list[State] | None:
            a = legs0.above_state((ix[0], ix[1]), down=False) if legs0 is not None else home
            b = legs1.above_state((ix[2], ix[3]), down=True) if legs1 is not None else home
            if not (within_limits(a, self.limits) and within_limits(b, self.limits)):
                return None
            return [a, *middle, b]

        def across(ix: Pair) -> float:
            if ix not in across_memo:
                states = states_across(ix)
                chain = None
                if states is not None:
                    ends = self.ruckig.chain(states[:2]) if middle else None
                    tail = self.ruckig.chain(states[-2:]) if middle else None
                    if middle and ends is not None and tail is not None and fixed is not None:
                        chain = [*ends, *fixed, *tail]
                    elif not middle:
                        chain = self.ruckig.chain(states)
                dur = sum(t.duration for t in chain) if chain is not None else math.inf
                across_memo[ix] = (float(dur), states or [], chain)
            return across_memo[ix][0]

        def bound(legs: SlotLegs | None) -> Callable[[Cell], float]:
            return legs.lower_bound if legs is not None else lambda _: 0.0

        def exact(legs: SlotLegs | None, exit_leg: bool) -> Callable[[Cell], float]:
            def duration(cell: Cell) -> float:
                pair = legs.legs(cell) if legs is not None else None
                if legs is None:
                    return 0.0
                return math.inf if pair is None else pair[1 if exit_leg else 0].duration
            return duration

        start0 = _search_start(legs0) if legs0 is not None else (0, 0)
        start1 = _search_start(legs1) if legs1 is not None else (0, 0)
        rest0 = legs0.rest_cell if legs0 is not None else (0, 0)
        rest1 = legs1.rest_cell if legs1 is not None else (0, 0)
        ix = best_cells((*n0, *n1), (*start0, *start1), (bound(legs0), bound(legs1)),
                        (exact(legs0, True), exact(legs1, False)), across, (*rest0, *rest1))
        total = exact(legs0, True)((ix[0], ix[1])) + exact(legs1, False)((ix[2], ix[3])) + across(ix)
        if not math.isfinite(total):
            raise PlanError(f"no feasible connection from {_slot_name(slot0)} to {_slot_name(slot1)}: even the "
                            "rest-to-rest motion failed")
        _, states, chain = across_memo[ix]
        assert chain is not None
        pair0 = legs0.legs((ix[0], ix[1])) if legs0 is not None else None
        pair1 = legs1.legs((ix[2], ix[3])) if legs1 is not None else None
        exit_leg = pair0[1] if pair0 is not None else None
        entry_leg = pair1[0] if pair1 is not None else None
        if self.blend and legs0 is not None and legs1 is not None and exit_leg is not None and entry_leg is not None:
            assert slot0 is not None and slot1 is not None
            d = contact_point_world(self.station, *slot1) - contact_point_world(self.station, *slot0)
            d[2] = 0.0
            if np.linalg.norm(d) > 1e-9:
                d /= np.linalg.norm(d)
                blender = Blender(self.ruckig, self.limits, self.tol_m)
                exit_leg, states, chain = blender.side(legs0, exit_leg, states, chain, self._lateral(slot0, d), True)
                entry_leg, states, chain = blender.side(legs1, entry_leg, states, chain, self._lateral(slot1, d),
                                                        False)
        cells = ((ix[0], ix[1]) if legs0 is not None else None, (ix[2], ix[3]) if legs1 is not None else None)
        return Connection(exit_leg, tuple(states), tuple(chain), entry_leg, cells)

    def _lateral(self, slot: Slot, d_world: FloatArray) -> FloatArray:
        """Joint velocity [rad/s] moving the suction point at the slot's above pose horizontally at 1 m/s along
        ``d_world``."""
        robot = load_ur3(self.station.tool, self.station.limits, self.station.robot)
        q = self.q_above(slot)
        R_world_tcp = self.station.T_world_base.rotation @ robot.fk(q, "tcp").rotation
        return lateral_direction(robot.frame_jacobian_local(q, "tcp"), R_world_tcp, d_world)

    # ----------------------------------------------------------------------------------------------- references

    def rest_to_rest(self, q0: FloatArray, q1: FloatArray) -> float:
        """Duration [s] of the joint-space Ruckig motion from rest at ``q0`` to rest at ``q1`` (memoized)."""
        key = (q0.tobytes(), q1.tobytes())
        if key not in self._rest:
            z = self._zero
            sol = self.ruckig.solve(q0, z, z, q1, z, z)
            if sol.trajectory is None:
                raise PlanError(f"Ruckig failed from {np.round(q0, 4).tolist()} to {np.round(q1, 4).tolist()}: "
                                f"{sol.reason}")
            self._rest[key] = sol.trajectory.duration
        return self._rest[key]

    def exact_vertical_leg(self, slot: Slot) -> float:
        """Duration [s] of the rest-to-rest leg that follows the slot's vertical line exactly: a 1-DoF Ruckig of the
        path coordinate under :class:`~ur3hanoi.plan.motion.vertical.PathLimits` (memoized)."""
        if slot not in self._exact_leg:
            vp = self.wp.vertical[slot[0]][slot[1]]
            pl = PathLimits.for_path(vp, self.limits)
            z = [0.0]
            sol = OfflineRuckig([pl.v], [pl.a], [pl.j]).solve(z, z, z, [vp.length_m], z, z)
            if sol.trajectory is None:
                raise PlanError(f"the exact vertical leg of {_slot_name(slot)} failed: {sol.reason}")
            self._exact_leg[slot] = sol.trajectory.duration
        return self._exact_leg[slot]


def _search_start(legs: SlotLegs) -> Cell:
    """The search start: the cell nearest :data:`SEARCH_START` (grid steps) whose lower bound is finite (the rest
    cell if none)."""
    def nearest(values: tuple[float, ...], target: float) -> int:
        return min(range(len(values)), key=lambda i: abs(values[i] - target))
    i0 = nearest(legs.speeds, SEARCH_START[0] * legs.vb)
    j0 = nearest(legs.accels, SEARCH_START[1] * legs.vb / legs.t_rest)
    n_i, n_j = legs.shape
    by_distance = sorted((abs(i - i0) + abs(j - j0), i, j) for i in range(n_i) for j in range(n_j))
    for _, i, j in by_distance:
        if math.isfinite(legs.lower_bound((i, j))):
            return i, j
    return legs.rest_cell


def _slot_name(slot: Slot | None) -> str:
    return "home" if slot is None else f"tower {slot[0] + 1} height {slot[1] + 1}"


@lru_cache(maxsize=8)
def _cached_planner(station: Station, v: tuple[float, ...], a: tuple[float, ...], j: tuple[float, ...], tol_m: float,
                    via_speeds: tuple[float, ...], via_accels: tuple[float, ...], pass_through: bool,
                    blend: bool) -> StationPlanner:
    limits = KinematicLimits(np.array(v), np.array(a), np.array(j))
    return StationPlanner(station, limits, tol_m, via_speeds, via_accels, pass_through, blend)


def station_planner(station: Station, limits: KinematicLimits, tol_m: float, via_speeds: tuple[float, ...],
                    via_accels: tuple[float, ...], pass_through: bool = True, blend: bool = True) -> StationPlanner:
    """The cached :class:`StationPlanner` of ``station`` under ``limits``, keyed by every input's value; of the
    station, by its geometry only (its name, source file and file digest do not change a motion)."""
    return _cached_planner(geometry_key(station), tuple(limits.v_max.tolist()), tuple(limits.a_max.tolist()),
                           tuple(limits.j_max.tolist()), float(tol_m), tuple(via_speeds), tuple(via_accels),
                           bool(pass_through), bool(blend))
