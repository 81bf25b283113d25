"""The one Ruckig wrapper of ur3hanoi: offline, time-optimal, jerk-limited trajectories that keep Ruckig's Result.

Offline only: every trajectory is one ``Ruckig.calculate`` of the open-source library between two full states
(position, velocity, acceleration per DoF). Intermediate waypoints are never set; with them the library would
send the problem to Ruckig's cloud service.

API:

- :class:`RuckigSolution` ``(result, trajectory, message)``: the outcome of one calculation. ``result`` is
  Ruckig's own ``ruckig.Result``; ``trajectory`` the ``ruckig.Trajectory`` (None unless ``ok``); ``message`` the
  text of a ``ruckig.RuckigError`` raised for invalid input (reported as ``Result.ErrorInvalidInput``).
  ``ok`` is True for ``Working``/``Finished`` (offline success is ``Working``; ``Finished`` only for a zero-length
  motion); ``reason`` is a one-line description for errors, e.g. ``"Ruckig ErrorExecutionTimeCalculation"``.
- :class:`OfflineRuckig` ``(v_max, a_max, j_max, *, velocity_control=False)``: one Ruckig instance for fixed
  limits and any number of DoFs. ``solve(q0, v0, a0, q1, v1, a1) -> RuckigSolution`` is the time-synchronized
  motion between two states. States may be lists or arrays; lists are the fast path (the segment builder
  converts its candidate states once and calls ``solve`` thousands of times). ``seconds`` accumulates the
  wall-clock time spent in ``solve`` [s] (the benchmark reads it through ``Plan.timings_s["ruckig"]``). With
  ``velocity_control`` Ruckig's ``ControlInterface.Velocity`` is used: the target velocity and acceleration are
  reached, the target position is ignored.
- :func:`to_rest` ``(q0, v0, a0, limits)`` and :func:`to_pose` ``(q0, v0, a0, q1, limits)``: from a state to rest
  (anywhere) or to rest at ``q1``; for a controller that must stop or go home from its current reference.
- :func:`control_samples` ``(trajectory, dt) -> (q, qd, qdd)``: the states at ``(i + 1) * dt`` [s] for
  ``i = 0 .. n - 1``, ``n = max(1, ceil(duration / dt))``, the last time clipped to the duration (so the last row
  is the final state): the references of the next ``n`` control cycles.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from ruckig import ControlInterface, InputParameter, Result, Ruckig, RuckigError
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.types import KinematicLimits

State = FloatArray | Sequence[float]
_SUCCESS = (Result.Working, Result.Finished)


@dataclass(frozen=True, slots=True)
class RuckigSolution:
    """One offline calculation: Ruckig's ``Result``, the trajectory if it succeeded, and any error text."""

    result: Result
    trajectory: RuckigTrajectory | None
    message: str = ""

    @property
    def ok(self) -> bool:
        return self.result in _SUCCESS

    @property
    def reason(self) -> str:
        """One line for error messages, e.g. ``"Ruckig ErrorInvalidInput: target velocity ... exceeds ..."``."""
        return f"Ruckig {self.result.name}" + (f": {self.message}" if self.message else "")


def _aslist(x: State) -> list[float]:
    if isinstance(x, list):  # the fast path: taken as is
        return x
    return x.tolist() if isinstance(x, np.ndarray) else [float(v) for v in x]


class OfflineRuckig:
    """One offline Ruckig instance with fixed limits [units of the DoFs: /s, /s^2, /s^3]; times its own calls."""

    def __init__(self, v_max: State, a_max: State, j_max: State, *, velocity_control: bool = False) -> None:
        self.dofs = len(v_max)
        self.otg = Ruckig(self.dofs)
        self.inp = InputParameter(self.dofs)
        self.inp.max_velocity = [float(x) for x in v_max]
        self.inp.max_acceleration = [float(x) for x in a_max]
        self.inp.max_jerk = [float(x) for x in j_max]
        if velocity_control:
            self.inp.control_interface = ControlInterface.Velocity
        self.seconds = 0.0  # [s] spent in solve

    def solve(self, q0: State, v0: State, a0: State, q1: State, v1: State, a1: State) -> RuckigSolution:
        """Time-optimal (time-synchronized) motion from state (q0, v0, a0) to state (q1, v1, a1)."""
        t0 = time.perf_counter()
        inp = self.inp
        inp.current_position = _aslist(q0)
        inp.current_velocity = _aslist(v0)
        inp.current_acceleration = _aslist(a0)
        inp.target_position = _aslist(q1)
        inp.target_velocity = _aslist(v1)
        inp.target_acceleration = _aslist(a1)
        traj = RuckigTrajectory(self.dofs)
        message = ""
        try:
            result = self.otg.calculate(inp, traj)
        except RuckigError as e:  # Ruckig validates the input by raising (e.g. a state outside the limits)
            result, message = Result.ErrorInvalidInput, " ".join(str(e).replace("[ruckig]", "").split())
        self.seconds += time.perf_counter() - t0
        return RuckigSolution(result, traj if result in _SUCCESS else None, message)

    def chain(self, states: Sequence[tuple[State, State, State]]) -> list[RuckigTrajectory] | None:
        """One segment between each pair of consecutive states (q, v, a), or None as soon as one fails."""
        out = []
        for s0, s1 in itertools.pairwise(states):
            traj = self.solve(*s0, *s1).trajectory
            if traj is None:
                return None
            out.append(traj)
        return out


def to_rest(q0: State, v0: State, a0: State, limits: KinematicLimits) -> RuckigSolution:
    """From the state (q0, v0, a0) to rest, wherever that is (velocity control), under ``limits``."""
    zero = [0.0] * len(q0)
    return OfflineRuckig(limits.v_max, limits.a_max, limits.j_max, velocity_control=True).solve(
        q0, v0, a0, q0, zero, zero)


def to_pose(q0: State, v0: State, a0: State, q1: State, limits: KinematicLimits) -> RuckigSolution:
    """From the state (q0, v0, a0) to rest at ``q1``, under ``limits``."""
    zero = [0.0] * len(q0)
    return OfflineRuckig(limits.v_max, limits.a_max, limits.j_max).solve(q0, v0, a0, q1, zero, zero)


def control_samples(trajectory: RuckigTrajectory, dt: float) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(q, qd, qdd), each (n, dofs), at times ``min((i + 1) * dt, duration)`` [s], ``n = max(1, ceil(duration/dt))``.

    Row ``i`` is the reference of the control cycle ``i + 1`` cycles after the start; the last row is the end state.
    """
    duration = trajectory.duration
    n = max(1, math.ceil(duration / dt))
    dofs = trajectory.degrees_of_freedom
    qs, vs, accs = np.empty((n, dofs)), np.empty((n, dofs)), np.empty((n, dofs))
    for i in range(n):
        qs[i], vs[i], accs[i] = trajectory.at_time(min((i + 1) * dt, duration))
    return qs, vs, accs
