"""The servo law of the simulated UR controller: how the joint reference becomes actuator commands, one control cycle
at a time. ``solve``'s executor (:func:`ur3hanoi.sim.run_plan`) and the ``movej`` world the ROS servers run
(:class:`ur3hanoi.sim.MoveJWorld`) both step the task scene through :class:`JointServo`.

The arm's actuators are MuJoCo position servos, force ``kp (ctrl - q) - kv qd`` (:data:`ur3hanoi.sim.DRIVES`).
In control cycle k, physics step j of n is commanded

    ``ctrl = c[k-1] + (j + 1/2) / n * (c[k] - c[k-1]) + M(q) a[k] / kp``,  with  ``c[k] = q_ref[k] + (kv/kp) qd_ref[k]``

- velocity feed-forward: the servo force is then ``kp (q_ref - q) + kv (qd_ref - qd)``;
- interpolation: the command moves linearly from ``c[k-1]`` to ``c[k]`` over the cycle, like a UR controller
  interpolating its servo targets, and each physics step holds the mean of that line over the step. A zero-order
  hold of the end sample would lead the reference by a full cycle (measured: 0.67 deg error at the wrist instead of
  0.13 deg); holding the cycle's mean lags it by half a cycle, which the stiff servo paid for with kp * v * 4 ms of
  torque: the wrists saturated at 12 N m returning home after a halt;
- acceleration feed-forward (:attr:`ur3hanoi.sim.SimConfig.accel_feedforward`): ``a[k]``, the mean of the
  reference accelerations at samples k-1 and k, times the joint-space inertia ``M(q)`` (armature included) at the
  pose the cycle starts from: the servo force gains ``M(q) qdd_ref``, as the UR controller moves on a model of its
  arm.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.robot.urdf import JOINT_NAMES
from ur3hanoi.sim.scene import TaskScene


class JointServo:
    """The arm's servos in a task scene, commanded once per control cycle (see the module docstring).

    Args:
        scene: the task scene whose arm it drives.
        period_s: the control period [s], a multiple of the scene's physics step.
        accel_feedforward: add ``M(q) a[k] / kp`` to the command.

    Raises:
        SimulationError: ``period_s`` is not a multiple of the physics step.
    """

    def __init__(self, scene: TaskScene, period_s: float, accel_feedforward: bool = True) -> None:
        m = scene.model
        n_steps = round(period_s / m.opt.timestep)
        if n_steps < 1 or abs(n_steps * m.opt.timestep - period_s) > 1e-9:
            raise SimulationError(f"control period {period_s} s is invalid: expected a multiple of the physics step "
                                  f"{m.opt.timestep} s")
        self.scene = scene
        self.period_s = period_s
        self.n_steps = n_steps
        self.accel_feedforward = accel_feedforward
        self.act_ids = np.array([m.actuator(j.removesuffix("_joint")).id for j in JOINT_NAMES])
        self.kp: FloatArray = m.actuator_gainprm[self.act_ids, 0]
        kv = -m.actuator_biasprm[self.act_ids, 2]
        self.ff: FloatArray = kv / self.kp  # velocity feed-forward gain [s]
        self._ramp = (np.arange(n_steps) + 0.5) / n_steps  # each physics step's mean point on the cycle's line
        self._acc_vec, self._acc_res = np.zeros(m.nv), np.zeros(m.nv)
        self.last_command: FloatArray = scene.arm_q()  # the command at the end of the last cycle [rad]
        self.last_acc: FloatArray = np.zeros(N_JOINTS)  # the reference acceleration at its end [rad/s^2]

    def command(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        """The servo command ``q + (kv/kp) qd`` [rad] of reference positions [rad] and velocities [rad/s]; one
        sample or rows of samples (vectorised: the executor computes a plan's at once)."""
        return q + qd * self.ff

    def reset(self, command: FloatArray, acc: FloatArray | None = None) -> None:
        """Command ``command`` [rad] now, with ``acc`` [rad/s^2] (None: zero) as the last reference acceleration:
        the start of a reference."""
        self.scene.data.ctrl[self.act_ids] = command
        self.last_command = command
        self.last_acc = np.zeros(N_JOINTS) if acc is None else acc

    def cycle(self, command: FloatArray, acc: FloatArray | None = None,
              after_first_step: Callable[[], None] | None = None) -> None:
        """One control cycle from the last command to ``command`` [rad] (see the module docstring), with the
        acceleration feed-forward of the reference acceleration ``acc`` [rad/s^2] at its end (None: none in this
        cycle, and zero at its end); ``after_first_step`` runs after the cycle's first physics step."""
        m, d = self.scene.model, self.scene.data
        offset: FloatArray | float = 0.0
        if acc is not None and self.accel_feedforward:
            self._acc_vec[self.scene.arm_dadr] = 0.5 * (self.last_acc + acc)
            mujoco.mj_mulM(m, d, self._acc_res, self._acc_vec)
            offset = self._acc_res[self.scene.arm_dadr] / self.kp
        start = self.last_command
        delta = command - start
        for j, r in enumerate(self._ramp):
            d.ctrl[self.act_ids] = start + r * delta + offset
            mujoco.mj_step(m, d)
            if j == 0 and after_first_step is not None:
                after_first_step()
        self.last_command = command
        self.last_acc = np.zeros(N_JOINTS) if acc is None else acc

    def track(self, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> None:
        """One control cycle to the reference sample ``q`` [rad], ``qd`` [rad/s], ``qdd`` [rad/s^2]."""
        self.cycle(self.command(q, qd), qdd)

    def hold(self, q: FloatArray) -> None:
        """One control cycle holding ``q`` [rad], without feed-forward: the arm at rest on its reference."""
        self.last_command = q
        self.cycle(q)
