"""Blending at the above points: start the motion across before the above pose, inside the vertical corridor.

At a via cell's above state the suction point moves only along the vertical line, so the joints that carry it
sideways (mostly the base) start the motion across from rest there. The corridor (``tol_m`` around the line)
leaves room to start them a little earlier: :class:`Blender` adds a horizontal velocity ``w`` [m/s] and
acceleration ``u`` [m/s^2] of the suction point toward the other slot to the via state (``w J^-1 e`` and
``u J^-1 e``, ``e`` the horizontal unit vector from one slot to the other; the acceleration is negative on the
entry side: the arm is ending its motion across). The exit side is blended first, then the entry side. (u, w)
minimise the duration of the two segments they change (the top segment of the leg and the adjacent segment across:
a small Nelder-Mead search, :func:`~ur3hanoi.plan.motion.minimize.nelder_mead`), and are then scaled back (bisection)
until the changed leg segment passes the same forward-kinematics check at 1 kHz as every leg
(:meth:`~ur3hanoi.plan.motion.legs.SlotLegs.corridor`). Measured gain (3 blocks): 1.1 % of the motion on lab_sim, 6 % on
lab_real, where every move turns the base (worst distance from the line 1.0 -> 1.8 mm there).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import replace

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.motion.corridor import CONTACT_OVERSHOOT_M, DENSE_MARGIN_M, Leg, State, within_limits
from ur3hanoi.plan.motion.legs import SlotLegs
from ur3hanoi.plan.motion.minimize import nelder_mead
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.types import KinematicLimits

# The search over (u, w) per side: u in units of the largest u the acceleration limits allow, w [m/s]. It starts
# near zero: the best blends of the lab stations are small (u 5-30 % of that largest u, w up to 0.05 m/s).
START = (0.05, 0.005)
STEP = (0.1, 0.01)
BLEND_EVALS = 30
CUTBACK_STEPS = 5  # bisection steps toward no blend when the corridor check fails


def _max_scale(state: State, h: FloatArray, limits: KinematicLimits, sign: float) -> float:
    """Largest ``k >= 0`` with ``a + sign k h`` within the acceleration limits."""
    a = state[2]
    out = math.inf
    for ai, hi, lim in zip(a.tolist(), (sign * h).tolist(), limits.a_max.tolist(), strict=True):
        if hi > 1e-12:
            out = min(out, (lim - ai) / hi)
        elif hi < -1e-12:
            out = min(out, (-lim - ai) / hi)
    return max(0.0, out) if math.isfinite(out) else 0.0


class Blender:
    """Adds the lateral via accelerations of :mod:`ur3hanoi.plan.motion.blend` to a connection's two above states."""

    def __init__(self, ruckig: OfflineRuckig, limits: KinematicLimits, tol_m: float) -> None:
        self.ruckig = ruckig
        self.limits = limits
        self.tol_m = tol_m

    def _solve(self, s0: State, s1: State) -> RuckigTrajectory | None:
        return self.ruckig.solve(*s0, *s1).trajectory

    def side(self, legs: SlotLegs, leg: Leg, across_states: list[State], across: list[RuckigTrajectory],
             h: FloatArray, exit_side: bool) -> tuple[Leg, list[State], list[RuckigTrajectory]]:
        """The leg and the motion across with the lateral acceleration added at one above pose (unchanged if it
        does not help or does not fit)."""
        if leg.path is not None or len(leg.states) < 3:
            return leg, across_states, across
        sign = 1.0 if exit_side else -1.0
        k_via = -1 if exit_side else 0  # the via state's index in the leg and in the motion across
        via = leg.states[k_via]
        inner = leg.states[-2] if exit_side else leg.states[1]
        nxt = across_states[1] if exit_side else across_states[-2]
        u_max = _max_scale(via, h, self.limits, sign)
        if u_max <= 0.0:
            return leg, across_states, across
        memo: dict[tuple[float, float], tuple[float, RuckigTrajectory | None, RuckigTrajectory | None]] = {}

        def state(x: Sequence[float]) -> State:
            return via[0], via[1] + x[1] * h, via[2] + sign * x[0] * h

        def trial(x: Sequence[float]) -> tuple[float, RuckigTrajectory | None, RuckigTrajectory | None]:
            key = (float(x[0]), float(x[1]))
            if key not in memo:
                s = state(x)
                top = across_seg = None
                if within_limits(s, self.limits) and x[0] >= 0.0 and x[1] >= 0.0:
                    top = self._solve(inner, s) if exit_side else self._solve(s, inner)
                    across_seg = self._solve(s, nxt) if exit_side else self._solve(nxt, s)
                cost = top.duration + across_seg.duration if top is not None and across_seg is not None else math.inf
                memo[key] = (cost, top, across_seg)
            return memo[key]

        base = trial((0.0, 0.0))[0]
        best = nelder_mead(lambda x: trial(x)[0], [START[0] * u_max, START[1]], [STEP[0] * u_max, STEP[1]],
                           max_evals=BLEND_EVALS)
        x = best.x
        if not trial(x)[0] < base:
            return leg, across_states, across

        def fits(lam: float) -> float | None:
            """The changed segment's deviation [m] at ``lam x`` if it passes the corridor check, else None."""
            top = trial((lam * x[0], lam * x[1]))[1]
            if top is None:
                return None
            dev, dip, near = legs.corridor.measure([top])
            ok = dev <= self.tol_m - DENSE_MARGIN_M and dip <= CONTACT_OVERSHOOT_M and legs.corridor.near_ok(near)
            return dev if ok else None

        dev = fits(1.0)
        if dev is None:  # cut back along the ray to the largest scale that fits (bisection)
            lo, hi = 0.0, 1.0
            for _ in range(CUTBACK_STEPS):
                mid = 0.5 * (lo + hi)
                d = fits(mid)
                if d is None:
                    hi = mid
                else:
                    lo, dev = mid, d
            if lo == 0.0 or dev is None or not trial((lo * x[0], lo * x[1]))[0] < base:
                return leg, across_states, across
            x = (lo * x[0], lo * x[1])
        _, top, across_seg = trial(x)
        assert top is not None and across_seg is not None
        s = state(x)
        states = list(leg.states)
        trajs = list(leg.trajectories)
        states[k_via] = s
        trajs[-1 if exit_side else 0] = top
        new_leg = replace(leg, states=tuple(states), trajectories=tuple(trajs),
                          duration=sum(t.duration for t in trajs), deviation_m=max(leg.deviation_m, dev))
        k_across = 0 if exit_side else -1
        across_states = list(across_states)
        across = list(across)
        across_states[k_across] = s
        across[k_across] = across_seg
        return new_leg, across_states, across


def lateral_direction(jacobian_local: FloatArray, R_world_tcp: FloatArray, d_world: FloatArray) -> FloatArray:
    """Joint velocity [rad/s] moving the suction point at 1 m/s along the world direction ``d_world`` without
    rotating the tool."""
    twist = np.concatenate([R_world_tcp.T @ d_world, np.zeros(3)])
    return np.asarray(np.linalg.solve(jacobian_local, twist), dtype=float)
