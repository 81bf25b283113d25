"""The segment builder: the hops of a move sequence, and their chained Ruckig segments.

Each move visits previous place -> above(src) -> on(src) -> [suction on, dwell] -> above(src) -> above(dst) ->
on(dst) -> [suction off, dwell] -> above(dst); the plan starts and ends at home with suction off. A *hop*
(:class:`Hop`) is everything between two dwells (or home): retreat/lift, the motion across, descend; the builder
turns each into a :class:`~ur3hanoi.plan.route.connections.Connection` and lays the connections and dwells end to end.
Every segment is one offline Ruckig calculation (:mod:`ur3hanoi.plan.motion.ruckig`); the end state of one is the start
state of the next.

- Pass-through: the robot does not stop at the above poses; the via states there, and the approach legs, are
  described in :mod:`ur3hanoi.plan.motion.legs` and :mod:`ur3hanoi.plan.motion.via`.
- Tall towers: a hop rises over the towers on its way when they are taller than its above poses
  (:func:`plan_hops`): to "over" points on the two slots' vertical lines, at rest, high enough for the carried block
  (or the empty cup) to clear the tallest stack on the towers it passes (the towers between the two, by index:
  the grid's towers stand in a row) by the clearance plus :data:`OVER_MARGIN_M`.
- Stop-and-go (``pass_through=False``): the same waypoints with zero velocity at each, the same dwells and limits.

Connections are memoized per station (:func:`~ur3hanoi.plan.route.connections.station_planner`): a Hanoi solve revisits
the same few slot pairs over and over, and a repeated hop reuses the same trajectories, hence the same segments.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import Move, stacks_before_moves
from ur3hanoi.plan.motion.corridor import Leg, State
from ur3hanoi.plan.route import stored
from ur3hanoi.plan.route.connections import Connection, StationPlanner, station_planner
from ur3hanoi.plan.types import Phase, PlanConfig, Segment
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import block_center_world, contact_point_world

Slot = tuple[int, int]  # (tower, height), 0-based
Step = tuple[Phase, int]  # (phase, move index) of a segment
# [m] extra height of the over points above the required clearance: the joint-space motion between two over points
# sags or bulges by a few millimetres; the clearance checks verify the result.
OVER_MARGIN_M = 0.015


@dataclass(frozen=True)
class Hop:
    """From the dwell at ``slot0`` to the dwell at ``slot1`` (None: home), with the steps of its three parts and
    the dwell that follows (None at the end). ``over0``/``over1``: world heights [m] to rise to over the slots
    (None: not needed)."""

    slot0: Slot | None
    slot1: Slot | None
    exit_step: Step
    across_step: Step
    entry_step: Step
    dwell_step: Step | None
    over0: float | None = None
    over1: float | None = None


def _label(pose: str, slot: Slot) -> str:
    return f"{pose}(t{slot[0] + 1},h{slot[1] + 1})"


def _clear_heights(station: Station, towers: Sequence[Sequence[int]], slot0: Slot | None, slot1: Slot | None,
                   carrying: bool, clearance_m: float) -> tuple[float | None, float | None]:
    """World heights [m] of the suction point over ``slot0``/``slot1`` that clear every resting block on the
    towers from one to the other (None where the above pose is high enough, or at home)."""
    if slot0 is None or slot1 is None:
        return None, None
    lo, hi = sorted((slot0[0], slot1[0]))
    tops = [float(block_center_world(station, t, h)[2]) + 0.5 * station.block_size
            for t in range(lo, hi + 1) for h in range(len(towers[t]))]
    if not tops:
        return None, None
    hang = station.block_size - station.contact_depth if carrying else 0.0  # carried block below the suction point
    need = max(tops) + hang + clearance_m
    z_above = [float(contact_point_world(station, *s)[2]) + station.approach for s in (slot0, slot1)]
    if min(z_above) >= need:
        return None, None
    over = max(need + OVER_MARGIN_M, *z_above)
    return (over if z_above[0] < over else None), (over if z_above[1] < over else None)


def plan_hops(station: Station, moves: Sequence[Move], n_blocks: int, start: int, clearance_m: float) -> list[Hop]:
    """The hops of ``moves`` from home to home (2 per move, plus the way home)."""
    stacks = stacks_before_moves(moves, n_blocks, start, station.n_towers)
    hops: list[Hop] = []
    prev: Slot | None = None
    prev_mi = -1
    for mi, m in enumerate(moves):
        src, dst = (m.from_tower, m.from_height), (m.to_tower, m.to_height)
        towers = stacks[mi]
        o0, o1 = _clear_heights(station, towers, prev, src, False, clearance_m)
        hops.append(Hop(prev, src, (Phase.RETREAT, prev_mi), (Phase.TRANSIT, mi), (Phase.DESCEND_PICK, mi),
                        (Phase.GRASP_DWELL, mi), o0, o1))
        resting = [list(t) for t in towers]
        resting[m.from_tower].pop()  # the carried block
        o0, o1 = _clear_heights(station, resting, src, dst, True, clearance_m)
        hops.append(Hop(src, dst, (Phase.LIFT, mi), (Phase.CARRY, mi), (Phase.DESCEND_PLACE, mi),
                        (Phase.RELEASE_DWELL, mi), o0, o1))
        prev, prev_mi = dst, mi
    hops.append(Hop(prev, None, (Phase.RETREAT, prev_mi), (Phase.HOME, -1), (Phase.HOME, -1), None))
    return hops


class _Chain:
    """Segments laid end to end in time."""

    def __init__(self) -> None:
        self.segments: list[Segment] = []
        self.t_end = 0.0

    def add(self, step: Step, s0: State, s1: State, traj: RuckigTrajectory | None, duration: float, target: str,
            leg: Leg | None = None) -> None:
        path = leg.path if leg is not None else None
        self.segments.append(Segment(step[0], step[1], self.t_end, duration, s0[0], s1[0], s0[1], s1[1], target,
                                     traj, path))
        self.t_end += duration


class SegmentBuilder:
    """Chains the segments of a move sequence on a station (pass-through or stop-and-go)."""

    def __init__(self, station: Station, config: PlanConfig, pass_through: bool | None = None) -> None:
        self.station = station
        self.config = config
        self.limits = config.limits(station)
        self.pass_through = config.pass_through if pass_through is None else pass_through
        self.planner: StationPlanner = station_planner(station, self.limits, config.vertical_tol_m,
                                                       config.via_speeds, config.via_accels, self.pass_through,
                                                       config.blend)
        self.legs_used: list[Leg] = []

    def _leg(self, chain: _Chain, step: Step, leg: Leg, slot: Slot, down: bool) -> None:
        n = len(leg.trajectories)
        for k, traj in enumerate(leg.trajectories):
            last = k == n - 1
            target = _label(("on" if down else "above") if last else "via", slot)
            s0, s1 = (leg.states[0], leg.states[-1]) if leg.path is not None else (leg.states[k], leg.states[k + 1])
            chain.add(step, s0, s1, traj, traj.duration, target, leg)
        self.legs_used.append(leg)

    def _hop(self, chain: _Chain, hop: Hop) -> Connection:
        c = stored.connect(self.planner, hop.slot0, hop.slot1, hop.over0, hop.over1)
        if c.exit is not None and hop.slot0 is not None:
            self._leg(chain, hop.exit_step, c.exit, hop.slot0, down=False)
        n = len(c.across)
        for k, traj in enumerate(c.across):
            if k < n - 1:
                over = hop.slot0 if (k == 0 and hop.over0 is not None) else hop.slot1
                assert over is not None
                target = _label("over", over)
            else:
                target = _label("above", hop.slot1) if hop.slot1 is not None else "home"
            chain.add(hop.across_step, c.across_states[k], c.across_states[k + 1], traj, traj.duration, target)
        if c.entry is not None and hop.slot1 is not None:
            self._leg(chain, hop.entry_step, c.entry, hop.slot1, down=True)
        if hop.dwell_step is not None and hop.slot1 is not None:
            q_on = c.entry.states[-1] if c.entry is not None else None
            assert q_on is not None
            zero = np.zeros(N_JOINTS)
            rest = (q_on[0], zero, zero)
            chain.add(hop.dwell_step, rest, rest, None, self.config.dwell_s, _label("on", hop.slot1))
        return c

    def build(self, hops: Sequence[Hop]) -> list[Segment]:
        """The chained segments of ``hops``, from home to home."""
        chain = _Chain()
        self.legs_used = []
        for hop in hops:
            self._hop(chain, hop)
        return chain.segments

    def q_above(self, slot: Slot | None) -> FloatArray:
        return self.planner.q_above(slot)
