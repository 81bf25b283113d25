"""Approach and retreat legs: joint-space Ruckig through interior IK points of a slot's vertical line.

A leg joins a slot's "above" pose, where the robot passes at a via state, and its contact ("on") pose, at rest.
The via state at the above pose moves the suction point along the vertical line: speed ``sigma`` [m/s] and path
acceleration ``accel`` [m/s^2] (joint velocity ``sigma q'(0)``, acceleration ``sigma^2 q''(0) + accel q'(0)``,
``q(s)`` the slot's :class:`~ur3hanoi.plan.motion.vertical.VerticalPath`). The candidates form a grid per slot
(:class:`SlotLegs`), in units of the slot's own rest-to-rest leg: ``vb = L / T0`` and ``vb / T0``, with ``L`` the
approach length and ``T0`` the joint-space rest-to-rest leg duration, so one grid fits every station and speed.

Method, and why (measured on lab_sim/lab_real, see ``bench/REPORT.md``):

- One joint-space Ruckig segment from above to on leaves the vertical line by 3-10 mm: the straight joint
  interpolation does not follow the curved ``q(s)``. Through ONE interior IK point on the line at 65 % of the
  approach, with its path speed and acceleration (2 numbers) chosen by
  :func:`~ur3hanoi.plan.motion.minimize.nelder_mead` (SciPy's Nelder-Mead), the leg stays within 0.5-1.6 mm of
  the line and takes the time of the single joint-space segment (within 0.1 % on most cells): that segment is a
  lower bound (any chain through a via point is also a motion between the same two states), so the search stops as soon
  as it comes within :data:`LOWER_BOUND_RTOL` of it. If one point
  is not enough for the corridor, two (at 1/3 and 2/3) are tried.
- Following the line exactly (a 1-DoF Ruckig of the path coordinate with limits constant over the path, from the
  worst derivatives) is 1.4-1.6x slower per leg: the joint derivatives vary ~10x along the path, so one constant
  limit is a structural ceiling. TOPP-RA (velocity and acceleration only) followed by a jerk-limited pass was the
  other candidate; the interior-point legs already reach the joint-space time, so no new dependency was needed.
- Near a singularity (a slot close to the base) the joint path curves so much at the contact end that one or two
  points dip into the block: such slots (:attr:`SlotLegs.hard`) use many points
  (:data:`~ur3hanoi.plan.motion.path_legs.PROFILE_POINTS`, spaced toward the contact) whose states come from the exact
  path timing; each segment is then at least as fast as that timing between its points, and the leg keeps the line. The
  exact path-following leg remains the last resort of the rest-to-rest cell, which therefore always has legs.
- Every leg is verified where it is built, once per (slot, via cell, direction), against the slot's
  :class:`~ur3hanoi.plan.motion.corridor.Corridor`: the suction point by forward kinematics every millisecond,
  within ``tol_m`` of the line and never more than :data:`~ur3hanoi.plan.motion.corridor.CONTACT_OVERSHOOT_M`
  below the contact pose (Ruckig's time-synchronised joints can settle a fraction of a millimetre past it; pressing
  a carried block into the stack below tilts the stack, so only 0.2 mm is allowed). Legs are shared by every
  connection that uses the cell, so a plan checks each distinct leg once.

Descend and lift are time reverses of each other (same duration by the symmetry of the limits); each is solved
and verified on its own. Every result is a pure function of (slot, cell): the cells of a slot can be built in any
order.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.plan.kinematics import tcp_positions_world
from ur3hanoi.plan.motion.corridor import (
    CONTACT_OVERSHOOT_M,
    DENSE_MARGIN_M,
    Cell,
    Corridor,
    Leg,
    State,
    within_limits,
)
from ur3hanoi.plan.motion.minimize import nelder_mead
from ur3hanoi.plan.motion.path_legs import exact_path_legs, profile_legs
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.motion.sampling import evaluate
from ur3hanoi.plan.motion.vertical import PathLimits
from ur3hanoi.plan.motion.waypoints import Waypoints
from ur3hanoi.plan.types import KinematicLimits
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON

INTERIOR_FRACTIONS: tuple[tuple[float, ...], ...] = ((0.65,), (1 / 3, 2 / 3), (0.25, 0.5, 0.75))  # in order
LOWER_BOUND_RTOL = 1e-3  # the interior search stops within this of the single-segment lower bound
# Start of the one-point search, in units (vb, vb / T0): the optima of the lab stations' legs lie at 1.7-1.95 vb
# and -2.6 to -4.5 vb / T0 over the whole via grid.
ONE_POINT_GUESS = (1.8, -3.0)
SEARCH_STEP = (0.05, 0.5)  # initial simplex of the search, same units
MAX_EVALS = 24  # cost evaluations of the search per interior point
OVERSHOOT_BOUND_M = 5e-3  # [m] a single segment overshooting the contact pose by more marks its cell infeasible


class SlotLegs:
    """The legs of one slot for every via cell, built on demand and memoized (deterministic in the cell).

    Args:
        station, wp, slot: the station, its waypoints and the slot (tower, height), 0-based.
        ruckig: the 6-DoF Ruckig instance of the planning limits.
        limits: the planning limits.
        speeds, accels: the via grid, in units of ``vb`` and ``vb / T0`` (see the module docstring).
        tol_m: allowed distance [m] of the suction point from the vertical line.
    """

    def __init__(self, station: Station, wp: Waypoints, slot: tuple[int, int], ruckig: OfflineRuckig,
                 limits: KinematicLimits, speeds: Sequence[float], accels: Sequence[float], tol_m: float) -> None:
        self.station = station
        self.slot = slot
        self.path = wp.vertical[slot[0]][slot[1]]
        self.ruckig = ruckig
        self.limits = limits
        zero = np.zeros_like(self.path.q[0])
        self.q_above = wp.table[slot[0], slot[1], ABOVE]
        self.on: State = (wp.table[slot[0], slot[1], ON], zero, zero)
        self.corridor = Corridor(station, slot, tol_m)
        rest = ruckig.solve(self.q_above, zero, zero, *self.on)
        if rest.trajectory is None:
            raise PlanError(f"Ruckig failed on the rest-to-rest leg of slot {slot}: {rest.reason}")
        self.t_rest = rest.trajectory.duration  # T0 [s]
        # The grid unit: the rest-to-rest leg's mean speed, but at most a third of the largest via speed the joint
        # velocity limits allow at the above pose (slow limits make a leg velocity-bound, not jerk-bound).
        dq0 = np.abs(self.path.dq[0])
        sigma_max = float(np.min(limits.v_max[dq0 > 1e-9] / dq0[dq0 > 1e-9])) if np.any(dq0 > 1e-9) else math.inf
        self.vb = min(self.path.length_m / self.t_rest, sigma_max / 3.0)  # [m/s]
        self.speeds = tuple(float(f) * self.vb for f in speeds)  # sigma [m/s]
        self.accels = tuple(float(f) * self.vb / self.t_rest for f in accels)  # [m/s^2]
        self.rest_cell: Cell = (self.speeds.index(0.0) if 0.0 in self.speeds else -1,
                                self.accels.index(0.0) if 0.0 in self.accels else -1)
        self._lower: dict[Cell, tuple[float, RuckigTrajectory | None]] = {}
        self._legs: dict[Cell, tuple[Leg, Leg] | None] = {}
        self._hard: bool | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return len(self.speeds), len(self.accels)

    def above_state(self, cell: Cell, down: bool) -> State:
        """The via state at the above pose: moving down (descend) or up (lift) at the cell's speed [rad, rad/s,
        rad/s^2]. The lift state is the time reverse of the descend state (velocity negated)."""
        sigma, acc = self.speeds[cell[0]], self.accels[cell[1]]
        dq, ddq = self.path.dq[0], self.path.ddq[0]
        return self.q_above, (sigma if down else -sigma) * dq, sigma * sigma * ddq + acc * dq

    # ----------------------------------------------------------------------------------------------- bound

    def lower_bound(self, cell: Cell) -> float:
        """Duration [s] of the single joint-space segment from the cell's above state to rest on: a lower bound of
        its leg (inf: the state is outside the limits, Ruckig fails, or the segment overshoots the contact pose by
        more than :data:`OVERSHOOT_BOUND_M`: the state cannot brake within the approach)."""
        return self._lower_bound(cell)[0]

    def _lower_bound(self, cell: Cell) -> tuple[float, RuckigTrajectory | None]:
        if cell not in self._lower and cell != self.rest_cell and self.hard:
            pl = self._path_limits()  # a hard slot's legs follow the path timing, which must admit the via state
            if self.speeds[cell[0]] > pl.v or abs(self.accels[cell[1]]) > pl.a:
                self._lower[cell] = (math.inf, None)
        if cell not in self._lower:
            a = self.above_state(cell, down=True)
            traj = self.ruckig.solve(*a, *self.on).trajectory if within_limits(a, self.limits) else None
            ok = traj is not None
            if traj is not None and cell != self.rest_cell:
                tau = np.linspace(0.0, traj.duration, 25)
                z = tcp_positions_world(self.station, evaluate(traj, tau)[0])[:, 2]
                ok = float(np.min(z)) >= self.corridor.z_on - OVERSHOOT_BOUND_M
            self._lower[cell] = (traj.duration, traj) if ok and traj is not None else (math.inf, None)
        return self._lower[cell]

    # ----------------------------------------------------------------------------------------------- legs

    def legs(self, cell: Cell) -> tuple[Leg, Leg] | None:
        """(descend, lift) of the cell, verified; None if the cell is infeasible. The rest cell always has legs
        (the exact path-following fallback if no interior-point leg fits the corridor)."""
        if cell not in self._legs:
            self._legs[cell] = self._build(cell)
        return self._legs[cell]

    def _search(self, cell: Cell, lb: float, fractions: Sequence[float], guess: Sequence[float],
                max_evals: int) -> tuple[tuple[float, ...], float]:
        """(interior states, duration [s]) of the fastest descend through interior points at ``fractions``."""
        above = self.above_state(cell, down=True)
        points = self._points(fractions)

        def cost(x: Sequence[float]) -> float:
            mid = self._interior_states(points, x, down=True)
            chain = self.ruckig.chain([above, *mid, self.on]) if mid is not None else None
            return sum(t.duration for t in chain) if chain is not None else math.inf

        n = len(fractions)
        step = [SEARCH_STEP[0] * self.vb, SEARCH_STEP[1] * self.vb / self.t_rest] * n
        best = nelder_mead(cost, guess, step, max_evals=max_evals, f_target=lb * (1.0 + LOWER_BOUND_RTOL))
        return best.x, best.fun

    @property
    def hard(self) -> bool:
        """True when one interior point makes even the rest-to-rest leg dip into the block (the joint path curves
        sharply at the contact end, near a singularity): more points at the same places would too, so the slot's
        other cells go straight to the many-point path-profile legs. A function of the slot alone."""
        if self._hard is None:
            lb, traj = self._lower_bound(self.rest_cell)
            self._hard = traj is None or self._through_points(self.rest_cell, lb, traj, INTERIOR_FRACTIONS[0])[1]
        return self._hard

    def _build(self, cell: Cell) -> tuple[Leg, Leg] | None:
        lb, traj = self._lower_bound(cell)
        if traj is None:
            return self._exact_path_legs() if cell == self.rest_cell else None
        for fractions in INTERIOR_FRACTIONS if not self.hard else ():
            legs, hopeless = self._through_points(cell, lb, traj, fractions)
            if legs is not None:
                return legs
            if hopeless:
                break
        legs = self._profile_legs(cell)
        if legs is None and cell == self.rest_cell:
            legs = self._exact_path_legs()
        return legs

    def _points(self, fractions: Sequence[float]) -> list[tuple[FloatArray, FloatArray, FloatArray]]:
        """(q, dq/ds, d2q/ds2) of the path at each interior point."""
        return [self.path.evaluate(f * self.path.length_m)[:3] for f in fractions]

    def _interior_states(self, points: Sequence[tuple[FloatArray, FloatArray, FloatArray]], x: Sequence[float],
                         down: bool) -> list[State] | None:
        out = []
        for k, (q, dq, ddq) in enumerate(points):
            sd = x[2 * k] if down else -x[2 * k]
            st = (q, sd * dq, sd * sd * ddq + x[2 * k + 1] * dq)
            if not within_limits(st, self.limits):
                return None
            out.append(st)
        return out

    def _initial_guess(self, traj: RuckigTrajectory, fractions: Sequence[float]) -> list[float]:
        """Path speed and acceleration of the single joint-space segment where its suction point crosses each
        interior point's height (projected on the path tangent): the chain starts next to that segment."""
        tau = np.linspace(0.0, traj.duration, 41)
        q, qd, qdd = evaluate(traj, tau)
        z = tcp_positions_world(self.station, q)[:, 2]
        x: list[float] = []
        for f in fractions:
            _, dq, ddq, _ = self.path.evaluate(f * self.path.length_m)
            k = int(np.argmin(np.abs(z - (self.corridor.z_on + (1.0 - f) * self.path.length_m))))
            sd = float(qd[k] @ dq / (dq @ dq))
            x += [sd, float((qdd[k] - sd * sd * ddq) @ dq / (dq @ dq))]
        return x

    def _through_points(self, cell: Cell, lb: float, traj: RuckigTrajectory, fractions: Sequence[float]
                        ) -> tuple[tuple[Leg, Leg] | None, bool]:
        """Legs through interior points at ``fractions`` of the approach; (None, hopeless) if they do not fit
        (hopeless: they dip below the contact pose, or, at a moving via cell, leave the line by more than twice the
        tolerance: more points would not bring them back)."""
        if len(fractions) == 1:
            guess = [ONE_POINT_GUESS[0] * self.vb, ONE_POINT_GUESS[1] * self.vb / self.t_rest]
        else:
            guess = self._initial_guess(traj, fractions)
        x, fun = self._search(cell, lb, fractions, guess, MAX_EVALS * len(fractions))
        if not math.isfinite(fun):
            return None, False
        above = self.above_state(cell, down=True)
        points = self._points(fractions)
        legs = []
        for down in (True, False):
            mid = self._interior_states(points, x, down)
            if mid is None:
                return None, False
            states = [above, *mid, self.on] if down else [self.on, *mid[::-1], self.above_state(cell, down=False)]
            chain = self.ruckig.chain(states)
            if chain is None:
                return None, False
            dev, dip, near = self.corridor.measure(chain)
            if dip > CONTACT_OVERSHOOT_M:
                return None, True
            tol_m = self.corridor.tol_m
            if dev > tol_m - DENSE_MARGIN_M:  # far off (not at rest): braking too late, more points won't help
                return None, cell != self.rest_cell and dev > 2.0 * tol_m
            if down and not self.corridor.near_ok(near):  # closing in on the line: more points may straighten it
                return None, False
            legs.append(Leg(tuple(states), tuple(chain), sum(t.duration for t in chain), dev))
        return (legs[0], legs[1]), False

    def _path_limits(self) -> PathLimits:
        return PathLimits.for_path(self.path, self.limits)

    def _profile_legs(self, cell: Cell) -> tuple[Leg, Leg] | None:
        """See :func:`~ur3hanoi.plan.motion.path_legs.profile_legs`."""
        return profile_legs(self.path, self.corridor, self.ruckig, self.limits, self._path_limits(),
                            (self.above_state(cell, down=True), self.above_state(cell, down=False)), self.on,
                            self.speeds[cell[0]], self.accels[cell[1]])

    def _exact_path_legs(self) -> tuple[Leg, Leg]:
        """See :func:`~ur3hanoi.plan.motion.path_legs.exact_path_legs`."""
        return exact_path_legs(self.path, self.corridor, self._path_limits(), self.q_above, self.on, self.slot)
