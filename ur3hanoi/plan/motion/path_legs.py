"""Legs that follow a slot's vertical line by its exact path timing: the fallbacks of
:class:`~ur3hanoi.plan.motion.legs.SlotLegs` where interior-point legs do not fit.

The exact timing is a 1-DoF Ruckig trajectory of the path coordinate ``s`` [m] under
:class:`~ur3hanoi.plan.motion.vertical.PathLimits`. :func:`profile_legs` samples it at many interior points and
joins them by joint-space segments (each at least as fast as the path timing between its points);
:func:`exact_path_legs` is the path-following rest-to-rest leg itself, the last resort that always exists.
"""

from __future__ import annotations

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError
from ur3hanoi.plan.kinematics import tcp_positions_world
from ur3hanoi.plan.motion.corridor import Corridor, Leg, State, within_limits
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.motion.sampling import evaluate
from ur3hanoi.plan.motion.vertical import PathLimits
from ur3hanoi.plan.types import KinematicLimits, VerticalPath

PROFILE_POINTS = (4, 6, 8, 12)
"""Numbers of interior points of the path-profile legs, tried in order; they are spaced quadratically toward the
contact pose, where the joint path curves most (near the arm's singularities)."""


def profile_legs(path: VerticalPath, corridor: Corridor, ruckig: OfflineRuckig, limits: KinematicLimits,
                 pl: PathLimits, above: tuple[State, State], on: State, sigma: float, acc: float
                 ) -> tuple[Leg, Leg] | None:
    """(descend, lift) through many interior points whose states come from the exact path-following timing,
    entering at the via state ``above`` (descending, lifting) of path speed ``sigma`` [m/s] and acceleration
    ``acc`` [m/s^2]: for slots where the joint path curves too much for one or two points. With
    :data:`PROFILE_POINTS` points the legs stay on the line; no search. None when none passes ``corridor``."""
    L = path.length_m
    if sigma > pl.v or abs(acc) > pl.a:
        return None
    sol = OfflineRuckig([pl.v], [pl.a], [pl.j]).solve([0.0], [sigma], [acc], [L], [0.0], [0.0])
    traj = sol.trajectory
    if traj is None:
        return None
    tau = np.linspace(0.0, traj.duration, 4001)
    s, sd, sdd = (x[:, 0] for x in evaluate(traj, tau))
    if float(np.min(s)) < -1e-12 or float(np.max(s)) > L + 1e-12:
        return None
    for n in PROFILE_POINTS:
        mid = []
        for k in range(n):
            i = min(int(np.searchsorted(s, (1.0 - ((n - k) / (n + 1)) ** 2) * L)), len(s) - 1)
            q, dq, ddq, _ = path.evaluate(float(s[i]))
            mid.append((q, sd[i] * dq, sd[i] * sd[i] * ddq + sdd[i] * dq))
        if not all(within_limits(m, limits) for m in mid):
            continue
        down = corridor.verified(ruckig, [above[0], *mid, on], down=True)
        rev = [(q, -v, a) for q, v, a in mid[::-1]]
        up = corridor.verified(ruckig, [on, *rev, above[1]], down=False) if down is not None else None
        if down is not None and up is not None:
            return down, up
    return None


def exact_path_legs(path: VerticalPath, corridor: Corridor, pl: PathLimits, q_above: FloatArray, on: State,
                    slot: tuple[int, int]) -> tuple[Leg, Leg]:
    """Rest-to-rest (descend, lift) following the line exactly: a 1-DoF Ruckig of s under ``pl``."""
    rk = OfflineRuckig([pl.v], [pl.a], [pl.j])
    L = path.length_m
    z = [0.0]
    above: State = (q_above, on[1], on[2])
    legs = []
    for s0, s1, states in (([0.0], [L], (above, on)), ([L], [0.0], (on, above))):
        sol = rk.solve(s0, z, z, s1, z, z)
        if sol.trajectory is None:
            raise PlanError(f"the exact vertical leg of slot {slot} failed: {sol.reason}")
        q = path.evaluate_many(evaluate(sol.trajectory, np.linspace(0.0, sol.trajectory.duration, 200))[0][:, 0])[0]
        p = tcp_positions_world(corridor.station, q)
        dev = float(np.max(np.hypot(p[:, 0] - corridor.line_xy[0], p[:, 1] - corridor.line_xy[1])))
        legs.append(Leg(states, (sol.trajectory,), sol.trajectory.duration, dev, path))
    return legs[0], legs[1]


__all__ = ["PROFILE_POINTS", "exact_path_legs", "profile_legs"]
