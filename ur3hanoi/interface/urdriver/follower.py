"""The UR driver's scaled joint trajectory controller, without a middleware: goals in, a desired joint state per
control cycle out, results by the controller's rules. :class:`TrajectoryFollower` ports ros_controllers'
``JointTrajectoryController`` (noetic-devel: ``joint_trajectory_controller_impl.h``, ``init_joint_trajectory.h``,
``tolerances.h``, ``stop_trajectory_builder.h``) with Universal Robots' scaled update; what differs on ROS 2 comes
from its :class:`~ur3hanoi.interface.urdriver.profile.ControllerProfile`.

- **Time.** The controller's clock ("uptime") advances by ``period x speed scaling`` every cycle.
- **A new goal** (:meth:`TrajectoryFollower.submit`) is checked (:func:`~ur3hanoi.interface.urdriver.goal.check_goal`)
  and preempts the running one. ROS 1 (:func:`spliced_trajectory`): points not after the next cycle dropped (all in
  the past: INVALID_GOAL "Dropping all N trajectory point(s) ..."), a bridge from the desired state; ROS 2
  (:func:`points_trajectory`): every point kept, the bridge from the *measured* state at the first sample. An empty
  trajectory stops the arm (ROS 1).
- **Every cycle** (:meth:`TrajectoryFollower.update`) the error is ``desired - actual`` (shortest angle). While the
  trajectory runs, a joint beyond its path tolerance aborts with PATH_TOLERANCE_VIOLATED; once it has ended, the goal
  succeeds when every joint is inside its goal tolerances (position, ``stopped_velocity_tolerance``), or aborts with
  GOAL_TOLERANCE_VIOLATED after the goal time. Tolerances: the profile's, a goal's own > 0 replacing, < 0 off.
- **Cancel** and aborts: ROS 1 ramps the desired state to rest (``stop_trajectory_duration``, lengthened to the
  deceleration limits), ROS 2 holds the measured position (``set_hold_position``).
- **The robot program** (:meth:`TrajectoryFollower.set_running`): the controller stops and starts with it.

The results are read with :meth:`TrajectoryFollower.take_outcomes`. Nothing here knows ROS, threads or MuJoCo.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ErrorCode
from ur3hanoi.interface.urdriver.goal import Rejection, TrajectoryGoal, check_goal
from ur3hanoi.interface.urdriver.profile import NOT_RUNNING, ControllerProfile
from ur3hanoi.interface.urdriver.spline import JointState, Segment, find_segment, segment

Status = Literal["succeeded", "aborted", "preempted", "canceled"]
BoolArray = npt.NDArray[np.bool_]
TIME_RESOLUTION_S = 1e-9
"""Times closer than this [s] are equal: ROS times are whole nanoseconds (the controllers compare them exactly)."""


@dataclass(frozen=True)
class Outcome:
    """How a goal ended: ``status``, the result's ``code`` and ``error_string``, at controller cycle ``cycle``;
    ``max_path_error_rad``: its largest position error while its trajectory ran."""

    key: Hashable
    status: Status
    code: ErrorCode
    error_string: str
    cycle: int
    max_path_error_rad: float = 0.0


@dataclass(frozen=True)
class Feedback:
    """The action feedback of one cycle: desired and actual joint states and their error (controller order)."""

    desired: JointState
    actual_q: FloatArray
    actual_qd: FloatArray
    error_q: FloatArray
    error_qd: FloatArray


@dataclass
class _Tolerances:
    """Per joint [rad, rad/s], 0 = not checked. (Acceleration tolerances are never violated: the controller's
    acceleration error is always 0.)"""

    path: FloatArray
    path_v: FloatArray
    goal: FloatArray
    goal_v: FloatArray
    goal_time_s: float
    bounds: tuple[FloatArray, ...] = ()  # path, path_v, goal, goal_v as bounds on |error| (inf: not checked)

    def seal(self) -> _Tolerances:
        """Fix :attr:`bounds` from the tolerances (once they are final): checked every cycle, so computed once."""
        self.bounds = tuple(np.where(x > 0.0, x, np.inf) for x in (self.path, self.path_v, self.goal, self.goal_v))
        return self


@dataclass
class _Active:
    key: Hashable
    tolerances: _Tolerances
    end_s: float  # controller time of the trajectory's last point
    accepted_cycle: int
    arrived: BoolArray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    max_path_error: float = 0.0


def _override(value: float, default: float) -> float:
    """``updateStateTolerances``: > 0 replaces, < 0 switches off (0), 0 keeps."""
    return value if value > 0.0 else 0.0 if value < 0.0 else default


def shortest_angle(a: FloatArray) -> FloatArray:
    """``angles::shortest_angular_distance``: ``a`` wrapped into [-pi, pi)."""
    return (a + np.pi) % (2.0 * np.pi) - np.pi


def goal_tolerances(profile: ControllerProfile, joints: tuple[str, ...], goal: TrajectoryGoal) -> _Tolerances:
    """The active goal's tolerances: the profile's defaults, the goal's own overrides (``updateStateTolerances``)."""
    p, n = profile, len(joints)
    tol = _Tolerances(np.full(n, p.path_tolerance_rad), np.zeros(n), np.full(n, p.goal_tolerance_rad),
                      np.full(n, p.stopped_velocity_tolerance), p.goal_time_s)
    index = {name: i for i, name in enumerate(joints)}
    for overrides, q_tol, v_tol in ((goal.path_tolerance, tol.path, tol.path_v),
                                    (goal.goal_tolerance, tol.goal, tol.goal_v)):
        for t in overrides:
            if t.name in index:
                i = index[t.name]
                q_tol[i], v_tol[i] = _override(t.position, q_tol[i]), _override(t.velocity, v_tol[i])
    tol.goal_time_s = _override(goal.goal_time_tolerance_s, tol.goal_time_s)
    return tol.seal()


def goal_states(goal: TrajectoryGoal, joints: tuple[str, ...]) -> list[JointState]:
    """The goal's points in the controller's joint order (absent fields None)."""
    order = [goal.joint_names.index(j) for j in joints]

    def pick(values: tuple[float, ...]) -> FloatArray | None:
        return np.array([values[k] for k in order], dtype=float) if values else None

    return [JointState(np.array([p.positions[k] for k in order], dtype=float), pick(p.velocities),
                       pick(p.accelerations)) for p in goal.points]


def points_trajectory(goal: TrajectoryGoal, joints: tuple[str, ...], start_s: float
                      ) -> tuple[list[Segment], tuple[float, JointState]]:
    """ROS 2: the segments between the goal's points from controller time ``start_s``, none dropped (the controller's
    ``Trajectory::sample``), and the first point: the controller bridges to it from the measured state at the first
    sample (``set_point_before_trajectory_msg(time, state_current_)``)."""
    times = [start_s + p.time_from_start_s for p in goal.points]
    states = goal_states(goal, joints)
    if len(states) == 1:
        return [segment(times[0], states[0], times[0], states[0])], (times[0], states[0])
    return ([segment(times[k], states[k], times[k + 1], states[k + 1]) for k in range(len(states) - 1)],
            (times[0], states[0]))


def spliced_trajectory(old: list[Segment], goal: TrajectoryGoal, joints: tuple[str, ...], now: float
                       ) -> list[Segment] | Rejection:
    """ROS 1: ``goal`` spliced into the running trajectory ``old`` at controller time ``now`` (points not after it
    dropped, a bridge from the desired state there), or INVALID_GOAL when every point lies in the past."""
    start = now + (goal.start_in_s or 0.0)
    times = [start + p.time_from_start_s for p in goal.points]
    first = next((k for k, t in enumerate(times) if t > now + TIME_RESOLUTION_S), None)
    if first is None:
        text = (f"Dropping all {len(goal.points)} trajectory point(s), as they occur before the current time.\n"
                f"Last point is {now - times[-1]:f}s in the past.")
        return Rejection(ErrorCode.INVALID_GOAL, text, text.replace("\n", " "))
    states = goal_states(goal, joints)
    bridge_from = max(start, now)
    keep = old[find_segment(old, now):find_segment(old, bridge_from) + 1]
    here = JointState(*old[find_segment(old, bridge_from)].sample(bridge_from))
    new = [*keep, segment(bridge_from, here, times[first], states[first])]
    return new + [segment(times[k], states[k], times[k + 1], states[k + 1]) for k in range(first, len(states) - 1)]


class TrajectoryFollower:
    """The scaled joint trajectory controller (see the module docstring).

    Args:
        profile: the controller's defaults and version rules.
        q0: the arm's position at start [rad] (controller joint order), held until the first goal.
        a_max: the joints' acceleration limits [rad/s^2], for the stop ramp on cancel.
        joints: the controller's joint names, in its order.
    """

    def __init__(self, profile: ControllerProfile, q0: Sequence[float] | FloatArray, a_max: Sequence[float],
                 joints: tuple[str, ...] = CONTROLLER_JOINTS) -> None:
        self.profile = profile
        self.joints = joints
        self.n = len(joints)
        self.a_max = np.asarray(a_max, dtype=float)
        q = np.array(q0, dtype=float)
        z = np.zeros(self.n)
        self.uptime = 0.0  # controller time [s]
        self.cycle = 0  # control cycles run
        self._last_period = 0.0  # the scaled period of the last cycle [s]
        self.trajectory: list[Segment] = [segment(0.0, JointState(q, z, z), 0.0, JointState(q, z, z))]
        self.desired = JointState(q.copy(), z.copy(), z.copy())
        self.active: _Active | None = None
        self._outcomes: list[Outcome] = []
        self._feedback: Feedback | None = None
        self.running = True
        self._measured = q.copy()  # the last cycle's measured position [rad] (ROS 2's ``state_current_``)
        self._bridge: tuple[float, JointState] | None = None  # ROS 2: a new goal's first point, bridged at 1st sample
        self._first_sample = False

    # ------------------------------------------------------------------------------------------------ goals
    def submit(self, key: Hashable, goal: TrajectoryGoal) -> Rejection | None:
        """Accept ``goal`` (it preempts the active one) or say why not. It starts at the next :meth:`update`."""
        if not self.running:
            return Rejection(ErrorCode.INVALID_GOAL, "", NOT_RUNNING)
        rejection = check_goal(goal, self.profile, self.joints)
        if rejection is not None:
            return rejection
        now = self.uptime + self._last_period  # the next update's controller time
        if self.profile.from_measured and goal.points:
            self._submit_from_measured(key, goal, now)
            return None
        if not goal.points:
            self._preempt()
            self.active = _Active(key, goal_tolerances(self.profile, self.joints, goal), now, self.cycle,
                                  np.zeros(self.n, dtype=bool))
            self._stop(now)
            self.active.end_s = self.trajectory[-1].end_s
            return None
        new = spliced_trajectory(self.trajectory, goal, self.joints, now)
        if isinstance(new, Rejection):
            return new
        self._preempt()
        self.trajectory = new
        self.active = _Active(key, goal_tolerances(self.profile, self.joints, goal), new[-1].end_s, self.cycle,
                              np.zeros(self.n, dtype=bool))
        return None

    def _submit_from_measured(self, key: Hashable, goal: TrajectoryGoal, now: float) -> None:
        new, self._bridge = points_trajectory(goal, self.joints, now + (goal.start_in_s or 0.0))  # bridged in update
        self._preempt()
        self.trajectory = new
        self.active = _Active(key, goal_tolerances(self.profile, self.joints, goal), new[-1].end_s, self.cycle,
                              np.zeros(self.n, dtype=bool))

    def _preempt(self) -> None:
        if self.active is not None:
            self._end("preempted", ErrorCode.SUCCESSFUL, "")

    def set_running(self, running: bool) -> None:
        """The controller stops and starts with the robot program (``controller_stopper``): stopping ends the
        active goal (ROS 2: aborted with ``deactivated_text``; ROS 1: preempted), the arm stops where it is, goals are
        refused (INVALID_GOAL, no ``error_string``); starting holds the measured position (``set_hold_position``)."""
        if self.running and not running and self.active is not None:
            if self.profile.deactivated_text:
                self._end("aborted", ErrorCode.INVALID_GOAL, self.profile.deactivated_text)
            else:
                self._preempt()
        if running != self.running:
            self._hold_measured()
        self.running = running

    def cancel(self, key: Hashable) -> bool:
        """Cancel goal ``key`` if it is the active one (True): it ends "canceled", the arm stops (:meth:`_halt`)."""
        if self.active is None or self.active.key != key:
            return False
        self._end("canceled", ErrorCode.SUCCESSFUL, "")
        self._halt()
        return True

    def _halt(self) -> None:
        """After a cancel or an abort: ROS 2 holds the measured position, ROS 1 ramps the desired state to rest."""
        if self.profile.from_measured:
            self._hold_measured()
        else:
            self._stop(self.uptime)

    def _hold_measured(self) -> None:
        """Hold the last cycle's measured position (``set_hold_position``: ``state_current_.positions``)."""
        z = np.zeros(self.n)
        here = JointState(self._measured.copy(), z, z)
        self._bridge = None
        self.trajectory = [segment(self.uptime, here, self.uptime, here)]

    def _end(self, status: Status, code: ErrorCode, text: str) -> None:
        assert self.active is not None
        self._outcomes.append(Outcome(self.active.key, status, code, text, self.cycle, self.active.max_path_error))
        self.active = None

    def take_outcomes(self) -> list[Outcome]:
        """The goals that ended since the last call, in order."""
        out, self._outcomes = self._outcomes, []
        return out

    # ------------------------------------------------------------------------------------------------- stop
    def _stop(self, t0: float) -> None:
        """Replace the trajectory by the ramp to rest from the desired state at controller time ``t0``."""
        assert self.desired.qd is not None  # the desired state always has every field
        self.trajectory = [stop_ramp(self.desired.q, self.desired.qd, t0, self.profile.stop_trajectory_s, self.a_max)]

    # ---------------------------------------------------------------------------------------------- cycle
    def update(self, q: FloatArray, qd: FloatArray, period_s: float, scaling: float) -> JointState:
        """One control cycle of ``period_s`` [s] at speed ``scaling`` (0..1) with the arm at ``q`` [rad], ``qd``
        [rad/s]: advance the clock, sample the desired state, check the active goal. Returns the desired state
        (its velocity and acceleration in controller time: times ``scaling`` and ``scaling**2`` on the wall)."""
        self.cycle += 1
        self._last_period = period_s * scaling
        t = self.uptime + (period_s if self.profile.sample_one_period_ahead else self._last_period)
        self.uptime += self._last_period
        self._first_sample = self._bridge is not None
        if self._bridge is not None:
            t_first, first = self._bridge
            self._bridge = None
            if t_first > t + TIME_RESOLUTION_S:
                self.trajectory.insert(0, segment(t, JointState(q.copy(), qd.copy(), None), t_first, first))
        self._measured = q.copy()
        index = find_segment(self.trajectory, t)
        seg = self.trajectory[index]
        p, v, a = seg.sample(t)
        self.desired = JointState(p, v, a)
        err_q, err_qd = shortest_angle(p - q), v - qd
        active = self.active
        self._feedback = None
        if active is not None:
            self._feedback = Feedback(self.desired, q.copy(), qd.copy(), err_q, err_qd)
            self._check(active, seg, index == len(self.trajectory) - 1, err_q, err_qd)
        return self.desired

    def _check(self, active: _Active, seg: Segment, last: bool, err_q: FloatArray, err_qd: FloatArray) -> None:
        tol, prof = active.tolerances, self.profile
        moving = self.uptime < seg.end_s - TIME_RESOLUTION_S
        if moving or self._first_sample:  # ROS 2 checks the first sample even when it is the last point
            active.max_path_error = max(active.max_path_error, float(np.abs(err_q).max()))
            bad = _outside(err_q, err_qd, tol.bounds[0], tol.bounds[1])
            if bad is not None:
                self._end("aborted", ErrorCode.PATH_TOLERANCE_VIOLATED,
                          prof.path_error.format(joint=self.joints[bad], error=float(err_q[bad]), late=0.0))
                if prof.hold_on_path_abort:
                    self._halt()
                return
        if moving:
            return
        if not last:
            return
        inside = _inside(err_q, err_qd, tol.bounds[2], tol.bounds[3])
        late = self.uptime - seg.end_s
        out_of_time = (not (prof.goal_time_zero_waits and tol.goal_time_s == 0.0)
                       and late >= tol.goal_time_s - TIME_RESOLUTION_S)
        if prof.validation == "ros1":  # per joint, in order; a joint once inside stays counted as arrived
            for i in range(self.n):
                if inside[i]:
                    active.arrived[i] = True
                elif out_of_time:
                    self._abort_late(i, err_q, late)
                    return
            if np.all(active.arrived):
                self._end("succeeded", ErrorCode.SUCCESSFUL, prof.success_text)
        elif np.all(inside):
            self._end("succeeded", ErrorCode.SUCCESSFUL, prof.success_text)
        elif out_of_time:
            self._abort_late(int(np.flatnonzero(~inside)[0]), err_q, late)

    def _abort_late(self, joint: int, err_q: FloatArray, late: float) -> None:
        prof = self.profile
        self._end("aborted", ErrorCode.GOAL_TOLERANCE_VIOLATED,
                  prof.goal_error.format(joint=self.joints[joint], error=float(err_q[joint]), late=late))
        if prof.hold_on_path_abort:
            self._halt()

    # ------------------------------------------------------------------------------------------- reading
    def feedback(self) -> Feedback | None:
        """The active goal's feedback of the last cycle (None without an active goal)."""
        return self._feedback

    @property
    def max_path_error(self) -> float:
        """The active goal's largest position error [rad] while its trajectory ran (0 without one)."""
        return 0.0 if self.active is None else self.active.max_path_error


def stop_ramp(q: FloatArray, qd: FloatArray, t0: float, duration_s: float, a_max: FloatArray) -> Segment:
    """The controller's stop trajectory (``StopTrajectoryBuilder``) from position ``q`` [rad] and velocity ``qd``
    [rad/s] at controller time ``t0``: the quintic to the middle of the mirror segment that returns to ``q`` at
    ``-qd`` after twice ``duration_s``, where the velocity is 0; lengthened where a joint would decelerate faster
    than ``a_max`` [rad/s^2] (the real robot limits its own). ``duration_s`` 0 or an arm at rest: hold ``q``."""
    z = np.zeros(len(q))
    T = duration_s
    if T <= 0.0 or not np.any(qd):
        return segment(t0, JointState(q, z, z), t0, JointState(q, z, z))
    for _ in range(2):  # the second pass checks the lengthened ramp
        mirror = segment(t0, JointState(q, qd, z), t0 + 2.0 * T, JointState(q, -qd, z))
        ramp = segment(t0, JointState(q, qd, z), t0 + T, JointState(*mirror.sample(t0 + T)))
        peak = np.max(np.abs([ramp.sample(t0 + T * u)[2] for u in np.linspace(0.0, 1.0, 21)]), axis=0)
        ratio = float(np.max(peak / a_max))
        if ratio <= 1.0:
            break
        T *= ratio
    return ramp


def _outside(err_q: FloatArray, err_qd: FloatArray, bound_q: FloatArray, bound_qd: FloatArray) -> int | None:
    """The first joint outside its tolerances (as :attr:`_Tolerances.bounds`: inf where 0 = not checked), or None
    (``checkStateTolerancePerJoint``)."""
    bad = (np.abs(err_q) > bound_q) | (np.abs(err_qd) > bound_qd)
    return int(bad.argmax()) if bad.any() else None


def _inside(err_q: FloatArray, err_qd: FloatArray, bound_q: FloatArray, bound_qd: FloatArray) -> BoolArray:
    return ~((np.abs(err_q) > bound_q) | (np.abs(err_qd) > bound_qd))


__all__ = ["Feedback", "Outcome", "TrajectoryFollower", "shortest_angle", "stop_ramp"]
