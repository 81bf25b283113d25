"""The simulated UR robot under a streaming trajectory controller (the official driver's scaled joint trajectory
controller): each control cycle a position target comes in, the robot moves towards it within its joint limits and
reports how much it had to slow down (its speed scaling).

:class:`ServoWorld` is a :class:`~ur3hanoi.sim.task_world.TaskWorld` (scene, servo, suction, blocks) driven per cycle by
:meth:`~ServoWorld.step`: the controller's target ``(q, qd, qdd)`` for the end of the cycle (velocity and acceleration
in wall time). The robot is not a perfect tracker:

- **Limits.** The robot's own reference follows the target exactly while that stays within the joints' speed and
  acceleration limits (the station's :class:`~ur3hanoi.robot.model.JointLimits`, with :data:`LIMIT_MARGIN`); a target
  that asks more is followed as fast as the limits allow (velocity clipped, then its change per cycle; a gap is
  closed at the speed from which the robot can still stop in it), and the robot falls behind.
- **Speed scaling.** It reports ``slider x own``: ``own`` drops to the fraction of the commanded step the robot could
  make whenever it had to limit, and recovers by :data:`SCALING_RECOVERY_PER_S` once it is back on the target. The
  scaled controller advances its trajectory time by ``period x scaling``, so a too-fast trajectory is followed more
  slowly and ends late, by the lag gathered while the robot was limited (the UR driver's documentation: a goal with
  a tight goal time fails when slowed, one without succeeds). The slider (``--speed-scaling``) scales the whole.
- **The arm.** The robot's reference goes through the one servo law (:class:`~ur3hanoi.sim.servo.JointServo`): MuJoCo
  joints with their torque limits track it with the lag they have.
- **Fault injection.** :meth:`ServoWorld.hold_arm` clamps the arm where it is for a while (a person or an obstacle
  holding it), however the servos push: the controller's path tolerance is what notices.
"""

from __future__ import annotations

import math

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.task_world import TaskWorld
from ur3hanoi.station.calibration import Station

LIMIT_MARGIN = 1.02
"""A target within ``LIMIT_MARGIN x`` the joint limits is followed exactly: the controller's quintic between the
samples of a plan at the limits overshoots them by a fraction of a percent."""
PEAK_ACCELERATION = 5.0
"""The robot follows a target's transients (a velocity step of linear interpolation, a scaling change) with up to
this many times the acceleration limits, as a real UR's servo does (the datasheet gives no joint acceleration; the
limits of :class:`~ur3hanoi.robot.model.JointLimits` are the planner's)."""
SCALING_CHANGE_PER_S = 2.0
"""How fast [1/s] the robot's own speed scaling changes (0.5 s from 1 to 0): the robot ramps its speed, so a target
asking too much is limited (and the robot falls behind) until the scaling has come down."""
HOLD_FRICTION_NM = 1000.0
"""The clamp of :meth:`ServoWorld.hold_arm`: dry friction [N m] on every arm joint, far beyond the UR3's joint torques
(MuJoCo's ``frictionloss`` constraint, stable at any stiffness)."""
_MOVING_EPS = 1e-9  # [rad/s] a reference slower than this is at rest (a drop waits for motion)
_EXACT = 1e-12  # [rad, rad/s] a reference this close to the target follows it exactly


def _within(x: FloatArray, y: FloatArray) -> bool:
    """``np.allclose(x, y, rtol=0, atol=1e-12)`` for a finite ``x``: every element within 1e-12 of ``y`` (False
    where ``y`` is not finite)."""
    return bool(np.abs(x - y).max() <= _EXACT)


class ServoWorld(TaskWorld):
    """The robot of a streaming controller (see the module docstring).

    Args:
        station, start, n_blocks, removed, config, drop_on_grasp: as :class:`~ur3hanoi.sim.task_world.TaskWorld`.
        slider: the pendant's speed slider, in (0, 1].
    """

    def __init__(self, station: Station, start: int, n_blocks: int, removed: int | None = None,
                 config: SimConfig | None = None, drop_on_grasp: int | None = None, slider: float = 1.0) -> None:
        if not 0.0 < slider <= 1.0:
            raise SimulationError(f"speed slider {slider!r} is invalid: expected 0 < slider <= 1")
        super().__init__(station, start, n_blocks, removed, config, drop_on_grasp)
        lim = station.limits
        self.v_max = np.asarray(lim.v_max, dtype=float) * LIMIT_MARGIN
        self.a_max = np.asarray(lim.a_max, dtype=float) * LIMIT_MARGIN
        # Per-cycle constants of _limit (the same products it computed every cycle, in the same order).
        self._a_peak = self.a_max * PEAK_ACCELERATION
        self._two_a_peak = 2.0 * self.a_max * PEAK_ACCELERATION
        self._dv_peak = self._a_peak * self.config.period_s
        self._inf = np.full(len(self.v_max), np.inf)
        self.slider = slider
        self.own_scaling = 1.0
        self.ref_q: FloatArray = station.q_home_array.copy()  # the robot's own reference [rad]
        self.ref_qd: FloatArray = np.zeros_like(self.ref_q)  # [rad/s]
        self._target: FloatArray = self.ref_q.copy()  # the last target [rad]
        self.limited = False  # the last cycle had to limit the target
        self._motion_s: float | None = None
        self._hold_left = 0.0
        self._friction = self.scene.model.dof_frictionloss[self.scene.arm_dadr].copy()

    @property
    def speed_scaling(self) -> float:
        """What the robot reports: the slider times its own slowdown (0..1)."""
        return self.slider * self.own_scaling

    @property
    def lag(self) -> FloatArray:
        """The target minus the robot's reference [rad] (non-zero while the robot is behind)."""
        return self._target - self.ref_q

    def hold_arm(self, seconds: float) -> None:
        """Clamp the arm where it is for ``seconds`` of world time (0 releases it)."""
        self._hold_left = max(0.0, float(seconds))
        m, adr = self.scene.model, self.scene.arm_dadr
        m.dof_frictionloss[adr] = HOLD_FRICTION_NM if self._hold_left > 0.0 else self._friction

    @property
    def held(self) -> bool:
        """True while :meth:`hold_arm` clamps the arm."""
        return self._hold_left > 0.0

    def _limit(self, target: FloatArray) -> tuple[FloatArray, FloatArray]:
        """The robot's reference and velocity for this cycle towards ``target`` (see the module docstring)."""
        # Once per control cycle (500 Hz on an e-Series): plain ufuncs, not np.clip/np.allclose (whose Python
        # wrappers cost more than the arithmetic; the results are the same).
        dt = self.config.period_s
        step = target - self._target  # the target's own motion this cycle
        gap = self._target - self.ref_q  # how far behind the robot was
        abs_gap = np.abs(gap)
        close = np.sign(gap) * np.minimum(abs_gap / dt, np.sqrt(self._two_a_peak * abs_gap))
        want = step / dt + close
        qd = np.minimum(np.maximum(want, self.ref_qd - self._dv_peak), self.ref_qd + self._dv_peak)
        qd = np.minimum(np.maximum(qd, -self.v_max), self.v_max)
        self.limited = not _within(qd, want)
        return self.ref_q + qd * dt, qd

    def _rescale(self, qd: FloatArray, qdd: FloatArray) -> None:
        """Move the robot's own scaling towards the largest at which the controller's trajectory (its velocity
        ``qd`` and acceleration ``qdd`` at the current scaling) fits the limits, at most
        :data:`SCALING_CHANGE_PER_S` per second."""
        s = self.speed_scaling
        if s <= 0.0:
            return
        v, a = np.abs(qd) / s, np.abs(qdd) / (s * s)  # the trajectory's own, in its time
        # limit / 0 = inf, without np.errstate (a costly context manager at 500 Hz) to silence the warning
        fits_v = np.divide(self.v_max, v, out=self._inf.copy(), where=v != 0.0)
        fits_a = np.divide(self.a_max, a, out=self._inf.copy(), where=a != 0.0)
        fits = min(float(fits_v.min()), math.sqrt(float(fits_a.min())))
        goal = min(1.0, fits / self.slider)
        rate = SCALING_CHANGE_PER_S * self.config.period_s
        self.own_scaling = float(min(max(goal, self.own_scaling - rate), self.own_scaling + rate))

    def step(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> None:
        """One control cycle towards the controller's target ``q`` [rad] (with its wall-time velocity ``qd`` [rad/s]
        and acceleration ``qdd`` [rad/s^2], the servo's feed-forward while the robot follows it exactly): the
        robot's limits, the suction, the physics."""
        dt = self.config.period_s
        target = np.asarray(q, dtype=float)
        ref, ref_qd = self._limit(target)
        self._rescale(np.asarray(qd, dtype=float), np.asarray(qdd, dtype=float))
        exact = not self.limited and _within(ref, target)
        acc = np.asarray(qdd, dtype=float) if exact else (ref_qd - self.ref_qd) / dt
        vel = np.asarray(qd, dtype=float) if exact else ref_qd
        self.ref_q, self.ref_qd, self._target = (target.copy() if exact else ref), vel, target.copy()
        moving = bool((np.abs(vel) > _MOVING_EPS).any())
        self._motion_s = (0.0 if self._motion_s is None else self._motion_s + dt) if moving else None
        self._update_suction(self._motion_s)
        self._apply_hold(dt)
        self.servo.track(self.ref_q, vel, acc)

    def _apply_hold(self, dt: float) -> None:
        if self._hold_left > 0.0:
            self._hold_left -= dt
            if self._hold_left <= 1e-12:
                self.hold_arm(0.0)
