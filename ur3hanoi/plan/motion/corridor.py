"""The corridor of a slot's vertical line, and the legs checked against it.

Every approach or retreat leg (:mod:`ur3hanoi.plan.motion.legs`) and every blended top of a leg
(:mod:`ur3hanoi.plan.motion.blend`) is verified here, once where it is built: the suction point by forward
kinematics every millisecond (:data:`DENSE_RATE_HZ`), within the tolerance of the line (less
:data:`DENSE_MARGIN_M` for the samples in between), never more than :data:`CONTACT_OVERSHOOT_M` below the contact
pose, and within the placing band's tighter tolerance just above a stack (:func:`~ur3hanoi.plan.motion.vertical.
place_band`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.kinematics import tcp_positions_world
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.motion.sampling import evaluate
from ur3hanoi.plan.motion.vertical import place_band
from ur3hanoi.plan.types import KinematicLimits, VerticalPath
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import contact_point_world

State = tuple[FloatArray, FloatArray, FloatArray]  # joint position [rad], velocity [rad/s], acceleration [rad/s^2]
Cell = tuple[int, int]  # (via speed index, via acceleration index)

DENSE_RATE_HZ = 1000.0  # [Hz] rate of the forward-kinematics check of every leg
# [m] kept free below the tolerance at the 1 kHz samples: between two samples the suction point moves sideways by
# at most its lateral speed (< 0.05 m/s on a leg) times 0.5 ms, i.e. 25 um.
DENSE_MARGIN_M = 5e-5
# [m] a leg may dip this far below the contact pose (see the module docstring). 0.5 mm used to be allowed: at the
# 500 rad/s^3 jerk a carried block then pressed into the stack below and tilted it, leaving the placed block about
# 1 mm off per placement in MuJoCo (6 blocks on a 10-level grid ended 7.8 mm off); at 0.2 mm they stay within 2 mm
# and the lab plans are as fast (tests/plan/test_executes.py, bench/bench_executes.py).
CONTACT_OVERSHOOT_M = 2e-4


@dataclass(frozen=True)
class Leg:
    """One vertical leg in one direction: chained joint-space Ruckig segments through ``states``.

    Attributes:
        states: the K + 2 joint states, above -> interior points -> on (descend) or on -> ... -> above (lift).
        trajectories: the K + 1 Ruckig trajectories between them (joint space); for the exact path-following
            fallback, one 1-DoF trajectory of the path coordinate s [m] (``path`` set).
        duration: [s].
        deviation_m: worst distance [m] of the suction point from the vertical line (forward kinematics at 1 kHz).
        path: the slot's path when ``trajectories`` is the 1-DoF path-following trajectory, else None.
    """

    states: tuple[State, ...]
    trajectories: tuple[RuckigTrajectory, ...]
    duration: float
    deviation_m: float
    path: VerticalPath | None = None


def within_limits(state: State, limits: KinematicLimits) -> bool:
    """True when a via state is within the limits in Ruckig's sense: acceleration within ``a_max``, and velocity
    within ``v_max`` even after the acceleration is brought to zero at full jerk (``v + a |a| / (2 j)``).
    Otherwise Ruckig rejects it as a target, or starts from it with a brake profile that overshoots the velocity
    limit."""
    _, v, a = state
    if not (np.abs(a) <= limits.a_max).all():
        return False
    return bool((np.abs(v + a * np.abs(a) / (2.0 * limits.j_max)) <= limits.v_max).all())


class Corridor:
    """The vertical line of one slot (0-based tower, height) of ``station`` and what a leg may do around it.

    Attributes:
        line_xy: the line's horizontal position [m, world].
        z_on: height of the contact pose's suction point [m, world].
        band: ``(band above the contact pose [m], tolerance within it [m])`` when placing onto a stack, else None.
        tol_m: allowed distance [m] of the suction point from the line.
    """

    def __init__(self, station: Station, slot: tuple[int, int], tol_m: float) -> None:
        self.station = station
        contact = contact_point_world(station, *slot)
        self.line_xy = contact[:2]
        self.z_on = float(contact[2])
        self.band = place_band(slot[1])  # placing onto a stack: close to the line just above contact
        self.tol_m = tol_m

    def near_ok(self, near: float) -> bool:
        """True when the worst distance from the line within the slot's placing band (``near`` [m]) is allowed."""
        return self.band is None or near <= self.band[1] - DENSE_MARGIN_M

    def measure(self, chain: Sequence[RuckigTrajectory]) -> tuple[float, float, float]:
        """(worst distance [m] from the vertical line, deepest dip [m] below the contact pose, worst distance [m]
        from the line within the slot's placing band above the contact pose, 0 without a band) of chained joint
        trajectories, by forward kinematics at :data:`DENSE_RATE_HZ` (each segment from its start, and its end)."""
        q = np.concatenate([evaluate(t, np.append(np.arange(0.0, t.duration, 1.0 / DENSE_RATE_HZ), t.duration))[0]
                            for t in chain])
        p = tcp_positions_world(self.station, q)
        d = np.hypot(p[:, 0] - self.line_xy[0], p[:, 1] - self.line_xy[1])
        low = p[:, 2] <= self.z_on + self.band[0] if self.band is not None else np.zeros(len(d), dtype=bool)
        near = float(np.max(d[low])) if np.any(low) else 0.0
        return float(np.max(d)), max(0.0, self.z_on - float(np.min(p[:, 2]))), near

    def verified(self, ruckig: OfflineRuckig, states: Sequence[State], down: bool) -> Leg | None:
        """The leg chained by ``ruckig`` through ``states`` if it solves and passes the corridor check (and,
        descending, the placing band's), else None."""
        chain = ruckig.chain(states)
        if chain is None:
            return None
        dev, dip, near = self.measure(chain)
        if dip > CONTACT_OVERSHOOT_M or dev > self.tol_m - DENSE_MARGIN_M or (down and not self.near_ok(near)):
            return None
        return Leg(tuple(states), tuple(chain), sum(t.duration for t in chain), dev)


__all__ = ["CONTACT_OVERSHOOT_M", "DENSE_MARGIN_M", "DENSE_RATE_HZ", "Cell", "Corridor", "Leg", "State",
           "within_limits"]
