"""The motion of a halt after a suction fault: from the reference state to rest, and from rest to home.

:class:`HaltProfile` is what :func:`ur3hanoi.sim.run_plan` calls for both motions (its ``halt`` argument);
:data:`DEFAULT_HALT_PROFILE` is jerk-limited Ruckig within the station's limits, so the reference stays continuous
in position, velocity and acceleration through the halt.
"""

from __future__ import annotations

from typing import Protocol

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.plan import KinematicLimits, control_samples, to_pose, to_rest
from ur3hanoi.station.calibration import Station


class HaltProfile(Protocol):
    """The motion of a halt: samples (q, qd, qdd), each (n, 6) [rad, rad/s, rad/s^2], every ``dt`` [s] from the
    state (q0, v0, a0) to rest (``target_q`` None) or to rest at ``target_q``, within the station's limits with
    the velocity scaled by ``speed``. The first sample is ``dt`` after the start state.

    :func:`ur3hanoi.sim.run_plan` uses :data:`DEFAULT_HALT_PROFILE` unless given another one (``halt=``), e.g.
    to check that continuity checks catch a halt without a profile.
    """

    def __call__(self, q0: FloatArray, v0: FloatArray, a0: FloatArray, station: Station, speed: float, dt: float,
                 target_q: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray]: ...


def ruckig_halt(q0: FloatArray, v0: FloatArray, a0: FloatArray, station: Station, speed: float, dt: float,
                target_q: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Jerk-limited samples (q, qd, qdd) every ``dt`` [s] from a state to rest (``target_q`` None) or to a pose.

    Uses the project's one Ruckig wrapper (:mod:`ur3hanoi.plan.motion.ruckig`); a failure names Ruckig's result.
    """
    lim = station.limits
    # Stopping uses the full acceleration/jerk budget even at reduced speed: the arm must come to rest soon.
    limits = KinematicLimits(v_max=speed * np.asarray(lim.v_max, dtype=float),
                             a_max=np.asarray(lim.a_max, dtype=float), j_max=np.asarray(lim.j_max, dtype=float))
    solution = to_rest(q0, v0, a0, limits) if target_q is None else to_pose(q0, v0, a0, target_q, limits)
    if solution.trajectory is None:
        raise SimulationError(f"the halt trajectory could not be planned: {solution.reason}")
    return control_samples(solution.trajectory, dt)


DEFAULT_HALT_PROFILE: HaltProfile = ruckig_halt
"""The halt profile :func:`ur3hanoi.sim.run_plan` uses by default: jerk-limited Ruckig (:func:`ruckig_halt`)."""
