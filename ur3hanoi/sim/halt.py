"""The motion of a halt after a suction fault: from the reference state to rest, and from rest to home.

:class:`HaltProfile` is what :func:`ur3hanoi.sim.run_plan` calls for both motions (its ``halt`` argument);
:data:`DEFAULT_HALT_PROFILE` is jerk-limited Ruckig within the station's limits, so the reference stays continuous
in position, velocity and acceleration through the halt.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from ruckig import ControlInterface, InputParameter, Result, Ruckig
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.robot import N_JOINTS
from ur3hanoi.station import Station


class HaltProfile(Protocol):
    """The motion of a halt: samples (q, qd, qdd), each (n, 6) [rad, rad/s, rad/s^2], every ``dt`` [s] from the
    state (q0, v0, a0) to rest (``target_q`` None) or to rest at ``target_q``, within the station's limits with
    the velocity scaled by ``speed``. The first sample is ``dt`` after the start state.

    :func:`ur3hanoi.sim.run_plan` uses :data:`DEFAULT_HALT_PROFILE` unless given another one (``halt=``), e.g.
    to check that continuity checks catch a halt without a profile.
    """

    def __call__(self, q0: FloatArray, v0: FloatArray, a0: FloatArray, station: Station, speed: float, dt: float,
                 target_q: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray]: ...


def _ruckig_samples(q0: FloatArray, v0: FloatArray, a0: FloatArray, station: Station, speed: float, dt: float,
                    target_q: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Jerk-limited samples (q, qd, qdd) every ``dt`` [s] from a state to rest (``target_q`` None) or to a pose."""
    lim = station.limits
    otg = Ruckig(N_JOINTS)
    inp = InputParameter(N_JOINTS)
    inp.current_position = list(q0)
    inp.current_velocity = list(v0)
    inp.current_acceleration = list(a0)
    inp.target_velocity = [0.0] * N_JOINTS
    inp.target_acceleration = [0.0] * N_JOINTS
    inp.max_velocity = [speed * v for v in lim.v_max]
    # Stopping uses the full acceleration/jerk budget even at reduced speed: the arm must come to rest soon.
    inp.max_acceleration = list(lim.a_max)
    inp.max_jerk = list(lim.j_max)
    if target_q is None:
        inp.control_interface = ControlInterface.Velocity
        inp.target_position = list(q0)
    else:
        inp.target_position = list(target_q)
    traj = RuckigTrajectory(N_JOINTS)
    if otg.calculate(inp, traj) not in (Result.Working, Result.Finished):
        raise SimulationError("Ruckig could not plan the halt trajectory")
    n = max(1, math.ceil(traj.duration / dt))
    qs, vs, accs = np.empty((n, N_JOINTS)), np.empty((n, N_JOINTS)), np.empty((n, N_JOINTS))
    for i in range(n):
        qs[i], vs[i], accs[i] = traj.at_time(min((i + 1) * dt, traj.duration))
    return qs, vs, accs


DEFAULT_HALT_PROFILE: HaltProfile = _ruckig_samples
"""The halt profile :func:`ur3hanoi.sim.run_plan` uses by default: jerk-limited Ruckig (:func:`_ruckig_samples`)."""
