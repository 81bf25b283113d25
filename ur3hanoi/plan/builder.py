"""The segment builder: chains offline Ruckig segments through the waypoints of a move sequence.

Each move visits home/previous -> above(src) -> on(src) -> [suction on, dwell] -> above(src) -> above(dst) ->
on(dst) -> [suction off, dwell] -> above(dst); the plan ends at home with suction off. Every segment is one
offline Ruckig calculation (:mod:`ur3hanoi.plan.ruckig`); segments are chained: the end state of one is the start
state of the next.

- Vertical legs (descend, lift, retreat) follow the slot's :class:`~ur3hanoi.plan.vertical.VerticalPath`: a 1-DoF
  Ruckig trajectory of the path coordinate s [m] under :class:`~ur3hanoi.plan.vertical.PathLimits`.
- Pass-through: the robot does not stop at "above" waypoints. The via velocity there moves the suction point
  straight down (descend) or straight up (lift/retreat) at a Cartesian speed ``sigma`` [m/s]. ``sigma`` is picked
  per horizontal (transit/carry/home) segment from ``PlanConfig.via_fractions`` of the largest speed the vertical
  leg can brake from without overshooting the contact pose, minimising the summed duration of the exit leg, the
  horizontal segment and the entry leg (:func:`ur3hanoi.plan.via.best_via_pair`; the legs decouple: a via point
  joins exactly one vertical and one horizontal segment). A candidate whose calculation fails is dropped; zero
  (stop-and-go) is always a candidate.
- Stop-and-go (``pass_through=False``, the reference of ``Plan.stop_and_go_duration_s``): the same waypoints with
  zero velocity at each, the same dwells and limits.

A Hanoi solve revisits the same few slot pairs over and over (1023 moves use at most n_towers * n_heights slots),
and each Ruckig problem is deterministic in its inputs, so the builder memoizes them: a repeated leg or connection
reuses the same trajectory object, giving exactly the same segments. Shared trajectories are never mutated.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.grid import ABOVE, ON
from ur3hanoi.hanoi import Move
from ur3hanoi.plan.ruckig import OfflineRuckig, RuckigSolution
from ur3hanoi.plan.types import Phase, PlanConfig, Segment
from ur3hanoi.plan.vertical import PathLimits, VerticalPath, braking_speed
from ur3hanoi.plan.via import LegCandidates, best_via_pair
from ur3hanoi.plan.waypoints import Waypoints
from ur3hanoi.robot import N_JOINTS
from ur3hanoi.station import Station

Slot = tuple[int, int]  # (tower, height), 0-based
Step = tuple[Phase, int]  # (phase, move index) of a segment


@dataclass(frozen=True)
class Connection:
    """The best horizontal segment between two above points (or home): exit and entry via speeds [m/s] (0: at
    rest) and its joint-space Ruckig trajectory."""

    sigma_exit: float
    sigma_entry: float
    trajectory: RuckigTrajectory


def _label(pose: str, slot: Slot) -> str:
    return f"{pose}(t{slot[0] + 1},h{slot[1] + 1})"


def _stays_within(traj: RuckigTrajectory, lo: float, hi: float) -> bool:
    """True when the 1-DoF trajectory stays in [lo, hi] (no push past the contact pose or above the above pose)."""
    e = traj.position_extrema[0]
    return lo - 1e-12 <= e.min and e.max <= hi + 1e-12


class _Chain:
    """Segments laid end to end in time."""

    def __init__(self) -> None:
        self.segments: list[Segment] = []
        self.t_end = 0.0

    def add(self, step: Step, q0: FloatArray, v0: FloatArray, q1: FloatArray, v1: FloatArray,
            traj: RuckigTrajectory | None, duration: float, target: str, path: VerticalPath | None = None) -> None:
        self.segments.append(Segment(step[0], step[1], self.t_end, duration, q0, q1, v0, v1, target, traj, path))
        self.t_end += duration


class SegmentBuilder:
    """Chains Ruckig segments for a move sequence on a station (pass-through or stop-and-go)."""

    def __init__(self, station: Station, wp: Waypoints, config: PlanConfig, pass_through: bool = True) -> None:
        self.wp = wp
        self.config = config
        self.pass_through = pass_through and config.pass_through
        self.limits = config.limits(station)
        self.ruckig = OfflineRuckig(self.limits.v_max, self.limits.a_max, self.limits.j_max)
        self._legs: dict[Slot, LegCandidates] = {}
        self._path_ruckig: dict[Slot, tuple[OfflineRuckig, PathLimits]] = {}
        self._path_memo: dict[tuple[Slot, float, bool], tuple[RuckigSolution, bool]] = {}
        self._connections: dict[tuple[Slot | None, bytes, Slot | None, bytes], Connection] = {}
        self._zero = np.zeros(N_JOINTS)

    @property
    def ruckig_seconds(self) -> float:
        """Wall-clock time spent in Ruckig calculations so far [s]."""
        return self.ruckig.seconds + sum(r.seconds for r, _ in self._path_ruckig.values())

    # ------------------------------------------------------------------------------------------ vertical legs

    def _path(self, slot: Slot) -> tuple[VerticalPath, OfflineRuckig, PathLimits]:
        vp = self.wp.vertical[slot[0]][slot[1]]
        if slot not in self._path_ruckig:
            pl = PathLimits.for_path(vp, self.limits)
            self._path_ruckig[slot] = (OfflineRuckig([pl.v], [pl.a], [pl.j]), pl)
        rk, pl = self._path_ruckig[slot]
        return vp, rk, pl

    def _path_leg(self, slot: Slot, sigma: float, down: bool) -> tuple[RuckigSolution, bool]:
        """1-DoF Ruckig of s: down = above (entering at sigma [m/s]) -> on at rest; else on -> above (leaving at
        sigma), and whether it stays between the two poses. Memoized: the candidate search solves each once."""
        key = (slot, sigma, down)
        if key not in self._path_memo:
            vp, rk, _ = self._path(slot)
            z, L = [0.0], vp.length_m
            sol = rk.solve(z, [sigma], z, [L], z, z) if down else rk.solve([L], z, z, z, [-sigma], z)
            self._path_memo[key] = (sol, sol.trajectory is not None and _stays_within(sol.trajectory, 0.0, L))
        return self._path_memo[key]

    def legs(self, slot: Slot) -> LegCandidates:
        """Candidate via speeds of a slot's vertical leg, fastest first, with their durations (cached per slot)."""
        if slot not in self._legs:
            vp, _, pl = self._path(slot)
            smax = 0.999 * min(pl.v, braking_speed(vp.length_m, pl.a, pl.j))
            fractions = self.config.via_fractions if self.pass_through else (0.0,)

            def duration(sigma: float) -> float | None:
                sol, fits = self._path_leg(slot, sigma, down=True)
                return sol.trajectory.duration if fits and sol.trajectory is not None else None

            self._legs[slot] = LegCandidates([f * smax for f in sorted({*fractions, 0.0}, reverse=True)], duration)
        return self._legs[slot]

    def via_state(self, slot: Slot | None, sigma: float, down: bool) -> tuple[FloatArray, FloatArray]:
        """Joint (velocity [rad/s], acceleration [rad/s^2]) at the above pose of ``slot`` moving along its line at
        sigma [m/s] (down or up); zero for home (``slot`` None) or sigma 0."""
        if slot is None or sigma == 0.0:
            return np.zeros(N_JOINTS), np.zeros(N_JOINTS)
        vp = self.wp.vertical[slot[0]][slot[1]]
        v = sigma * vp.dq[0] if down else -sigma * vp.dq[0]
        return v, sigma * sigma * vp.ddq[0]  # the s-acceleration is zero at the via point

    # ------------------------------------------------------------------------------------ horizontal segments

    def connect(self, q0: FloatArray, slot0: Slot | None, q1: FloatArray, slot1: Slot | None) -> Connection:
        """The best connection from above ``slot0`` (left upward) to above ``slot1`` (entered downward); a None
        slot is home, at rest. Memoized: the key holds every input (the via states follow from the slots)."""
        key = (slot0, q0.tobytes(), slot1, q1.tobytes())
        if key not in self._connections:
            self._connections[key] = self._connect(q0, slot0, q1, slot1)
        return self._connections[key]

    def _connect(self, q0: FloatArray, slot0: Slot | None, q1: FloatArray, slot1: Slot | None) -> Connection:
        exits = self.legs(slot0) if slot0 is not None else LegCandidates.at_rest()
        entries = self.legs(slot1) if slot1 is not None else LegCandidates.at_rest()
        # Candidate states as lists (converted once per candidate, not per Ruckig call).
        q0l, q1l = q0.tolist(), q1.tolist()
        starts: dict[int, list[list[float]]] = {}
        ends: dict[int, list[list[float]]] = {}
        tried: dict[tuple[int, int], tuple[float, RuckigSolution | None]] = {}

        def cost(i: int, j: int) -> float:
            """Summed duration of exit leg i, the connection and entry leg j (inf: a leg or Ruckig failed)."""
            if (i, j) not in tried:
                l0, l1 = exits.get(i), entries.get(j)
                sol = None
                if l0 is not None and l1 is not None:
                    if i not in starts:
                        starts[i] = [x.tolist() for x in self.via_state(slot0, l0.sigma, down=False)]
                    if j not in ends:
                        ends[j] = [x.tolist() for x in self.via_state(slot1, l1.sigma, down=True)]
                    (v0, a0), (v1, a1) = starts[i], ends[j]
                    sol = self.ruckig.solve(q0l, v0, a0, q1l, v1, a1)
                if l0 is not None and l1 is not None and sol is not None and sol.trajectory is not None:
                    tried[(i, j)] = (l0.duration + sol.trajectory.duration + l1.duration, sol)
                else:  # a failed calculation drops the candidate (the next, smaller via speed is tried instead)
                    tried[(i, j)] = (math.inf, sol)
            return tried[(i, j)][0]

        i, j = best_via_pair(exits, entries, cost)
        sol = tried[(i, j)][1]
        l0, l1 = exits.get(i), entries.get(j)
        if sol is None or sol.trajectory is None or l0 is None or l1 is None:
            why = sol.reason if sol is not None else "no feasible vertical leg"
            raise PlanError(f"Ruckig could not connect {np.round(q0, 4).tolist()} to {np.round(q1, 4).tolist()}: "
                            f"{why}")
        return Connection(l0.sigma, l1.sigma, sol.trajectory)

    # ------------------------------------------------------------------------------------------------- chain

    def _vertical(self, chain: _Chain, step: Step, slot: Slot, sigma: float, down: bool) -> None:
        """A vertical leg of ``slot``: down from above (entering at sigma [m/s]) to on, or up (leaving at sigma)."""
        sol, fits = self._path_leg(slot, sigma, down)
        if not fits or sol.trajectory is None:
            why = sol.reason if not sol.ok else "the profile leaves the line between the above and on poses"
            raise PlanError(f"the vertical leg of tower {slot[0] + 1} height {slot[1] + 1} at {sigma:.4g} m/s "
                            f"failed: {why}")
        vp = self.wp.vertical[slot[0]][slot[1]]
        if down:
            q0, v0, q1, v1 = vp.q[0], self.via_state(slot, sigma, True)[0], vp.q[-1], self._zero
        else:
            q0, v0, q1, v1 = vp.q[-1], self._zero, vp.q[0], self.via_state(slot, sigma, False)[0]
        traj = sol.trajectory
        chain.add(step, q0, v0, q1, v1, traj, traj.duration, _label("on" if down else "above", slot), vp)

    def _through_vias(self, chain: _Chain, q0: FloatArray, slot0: Slot | None, up: Step, across: Step,
                      q1: FloatArray, slot1: Slot | None, down: Step) -> None:
        """Leave ``slot0`` upward (step ``up``), move across to above ``slot1`` (step ``across``) and descend into
        it (step ``down``), at the via speeds of the best connection. A None slot is home: no vertical leg."""
        c = self.connect(q0, slot0, q1, slot1)
        if slot0 is not None:
            self._vertical(chain, up, slot0, c.sigma_exit, down=False)
        traj = c.trajectory
        chain.add(across, q0, self.via_state(slot0, c.sigma_exit, False)[0], q1,
                  self.via_state(slot1, c.sigma_entry, True)[0], traj, traj.duration,
                  _label("above", slot1) if slot1 is not None else "home")
        if slot1 is not None:
            self._vertical(chain, down, slot1, c.sigma_entry, down=True)

    def _dwell(self, chain: _Chain, step: Step, slot: Slot) -> None:
        """At rest on the contact pose of ``slot`` for the suction to build up or release."""
        q_on = self.wp.table[slot[0], slot[1], ON]
        chain.add(step, q_on, self._zero, q_on, self._zero, None, self.config.dwell_s, _label("on", slot))

    def _above(self, slot: Slot) -> FloatArray:
        return self.wp.table[slot[0], slot[1], ABOVE]

    def build(self, moves: Sequence[Move]) -> list[Segment]:
        """The chained segments of ``moves``, from home to home.

        Per move: approach (retreat from the last place, transit, descend to pick), grasp dwell, carry (lift,
        carry, descend to place), release dwell. The retreat after a place waits for the next connection, which
        picks its exit speed.
        """
        chain = _Chain()
        q_prev: FloatArray = self.wp.q_home
        slot_prev: Slot | None = None  # None: at home
        prev_mi = -1  # the move whose retreat is pending
        for mi, m in enumerate(moves):
            src, dst = (m.from_tower, m.from_height), (m.to_tower, m.to_height)
            self._through_vias(chain, q_prev, slot_prev, (Phase.RETREAT, prev_mi), (Phase.TRANSIT, mi),
                               self._above(src), src, (Phase.DESCEND_PICK, mi))
            self._dwell(chain, (Phase.GRASP_DWELL, mi), src)
            self._through_vias(chain, self._above(src), src, (Phase.LIFT, mi), (Phase.CARRY, mi),
                               self._above(dst), dst, (Phase.DESCEND_PLACE, mi))
            self._dwell(chain, (Phase.RELEASE_DWELL, mi), dst)
            q_prev, slot_prev, prev_mi = self._above(dst), dst, mi
        self._through_vias(chain, q_prev, slot_prev, (Phase.RETREAT, prev_mi), (Phase.HOME, -1), self.wp.q_home,
                           None, (Phase.HOME, -1))
        return chain.segments
