"""Execute a plan in MuJoCo like the lab program: stream the reference, operate the suction, check the feedback,
halt on a fault, and verify the final block positions from the simulation state.

:func:`run_plan` runs four steps, each a method of one run (:class:`_Run`):

1. **streaming** (:meth:`_Run.stream_plan`): every control cycle sends the next trajectory sample through the
   servo (:class:`~ur3hanoi.sim.servo.JointServo`, the one servo law of the simulated controller), switches the
   suction at the plan's events and reads ``gripper_input``;
2. **suction check** (:class:`~ur3hanoi.sim.suction_check.SuctionCheck`, every cycle of step 1): a block must be
   held at the end of every GRASP_DWELL and in every cycle of a carrying phase, else streaming stops with a fault;
3. **halt** (:meth:`_Run.halt`, after a fault): decelerate to rest from the reference state (jerk-limited, no
   jump: :mod:`ur3hanoi.sim.halt`), suction off, vent, return home; then, as without a fault, hold the final
   pose while the blocks settle (:meth:`_Run.settle`);
4. **final verification** (:meth:`_Run.result`, :mod:`ur3hanoi.sim.verify`): where every block is, whether the arm
   is home and the suction off.

After a halt :func:`run_plan` raises :class:`ur3hanoi.errors.SuctionFaultError` carrying the :class:`SimResult`
(``error.result``): the lab program's halt condition is an error for the caller, with the full outcome attached.

Numbering: internally 0-based (towers, heights, blocks, moves); messages and JSON are 1-based like the lab.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import partial
from typing import Protocol

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError, SuctionFaultError
from ur3hanoi.plan import Phase, Plan, Trajectory
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.diagnosis import displaced_blocks
from ur3hanoi.sim.halt import DEFAULT_HALT_PROFILE, HaltProfile
from ur3hanoi.sim.result import DisplacedBlock, FeedbackEvent, JointTrace, SimResult
from ur3hanoi.sim.scene import TaskScene, build_task_scene, slot_centers, warning_counts
from ur3hanoi.sim.servo import JointServo
from ur3hanoi.sim.suction import GripperInput, SuctionCup
from ur3hanoi.sim.suction_check import Fault, SuctionCheck
from ur3hanoi.sim.verify import at_home, final_check, locate_blocks


@dataclass(frozen=True)
class Faults:
    """Injected faults (0-based). ``remove_block``: height left empty at spawn; ``drop_during_move``: index of
    the move during whose carry the suction loses its block (at the middle sample of its CARRY phase)."""

    remove_block: int | None = None
    drop_during_move: int | None = None


class FrameSink(Protocol):
    """Receives the simulation state at ``fps`` for rendering or viewing."""

    fps: float

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None: ...


ProgressFn = Callable[[float, str], None]


def _validate(plan: Plan, faults: Faults) -> tuple[int, int]:
    """The plan's start tower and block count, after checking that ``faults`` fit the plan."""
    moves = plan.moves
    if not moves:
        raise SimulationError("the plan has no moves")
    start = moves[0].from_tower
    n_blocks = max(m.block for m in moves) + 1
    if faults.remove_block is not None and not 0 <= faults.remove_block < n_blocks:
        raise SimulationError(f"Faults.remove_block = {faults.remove_block} is invalid: expected a 0-based height "
                              f"0..{n_blocks - 1}")
    if faults.drop_during_move is not None and not 0 <= faults.drop_during_move < len(moves):
        raise SimulationError(f"Faults.drop_during_move = {faults.drop_during_move} is invalid: expected a 0-based "
                              f"move 0..{len(moves) - 1}")
    return start, n_blocks


def _drop_sample(tr: Trajectory, faults: Faults) -> int:
    """The plan sample at which the injected drop happens (the middle of the move's CARRY phase), or -1."""
    if faults.drop_during_move is None:
        return -1
    ks = np.flatnonzero((tr.move_index == faults.drop_during_move) & (tr.phase == Phase.CARRY))
    if ks.size == 0:
        raise SimulationError(f"move {faults.drop_during_move + 1} has no CARRY phase to drop the block in")
    return int(ks[ks.size // 2])


class _Run:
    """One execution of a plan in a task scene: the state the steps of :func:`run_plan` share."""

    def __init__(self, plan: Plan, scene: TaskScene, faults: Faults, cfg: SimConfig, frames: FrameSink | None,
                 progress: ProgressFn | None, realtime: bool) -> None:
        self.plan, self.scene, self.cfg = plan, scene, cfg
        self.frames, self.progress, self.realtime = frames, progress, realtime
        m, d = scene.model, scene.data
        tr = self.tr = plan.trajectory
        self.servo = JointServo(scene, 1.0 / tr.rate_hz, cfg.accel_feedforward)
        # Start at rest on the first sample.
        d.qpos[scene.arm_qadr] = tr.q[0]
        d.qvel[scene.arm_dadr] = 0.0
        mujoco.mj_forward(m, d)
        self.commands = self.servo.command(tr.q, tr.qd)  # (N, 6) at once: the streaming loop is Python-bound
        self.servo.reset(self.commands[0], tr.qdd[0])
        self.cup = SuctionCup(scene, cfg.suction, seed=cfg.seed)
        self.events: list[FeedbackEvent] = []
        self.check = SuctionCheck(plan, scene, self.cup, cfg, self.events)
        self.drop_k = _drop_sample(tr, faults)
        self.drop_time: float | None = None
        self.max_err = 0.0
        self.moves_completed = 0
        self.trace: list[tuple[float, int, float]] = []  # (t [s], DIGIN, AIN0 [V]) every control cycle
        # Simulated joints every cycle and the reference streamed, chunk by chunk (see JointTrace).
        self.joints: list[tuple[float, FloatArray, FloatArray]] = [
            (float(d.time), d.qpos[scene.arm_qadr], d.qvel[scene.arm_dadr])]
        self.ref_chunks: list[tuple[FloatArray, FloatArray, FloatArray]] = []
        self.halt_start: int | None = None

        self.wall0 = time.perf_counter()
        self.frame_dt = 1.0 / frames.fps if frames is not None else math.inf
        self.next_frame = 0.0
        if frames is not None:
            frames(m, d)
            self.next_frame = self.frame_dt

    # ------------------------------------------------------------------------------------------ one control cycle

    def after_cycle(self) -> GripperInput:
        """After a control cycle of the servo: render, pace, record the joints, and read ``gripper_input`` like the
        driver does every cycle."""
        m, d = self.scene.model, self.scene.data
        if self.frames is not None and d.time + 1e-9 >= self.next_frame:
            self.frames(m, d)
            self.next_frame += self.frame_dt
        if self.realtime:
            lag = d.time - (time.perf_counter() - self.wall0)
            if lag > 0:
                time.sleep(lag)
        self.joints.append((float(d.time), d.qpos[self.scene.arm_qadr], d.qvel[self.scene.arm_dadr]))
        fb = self.cup.feedback()
        self.trace.append((fb.t, fb.digin, fb.ain0))
        return fb

    # ------------------------------------------------------------------------------------------ 1. streaming

    def stream_plan(self) -> Fault | None:
        """Stream the plan's samples 1.. until the end or the first failed suction check (returned)."""
        tr, d, cup, check, servo = self.tr, self.scene.data, self.cup, self.check, self.servo
        moves = self.plan.moves
        n = len(tr.t)
        report_every = max(1, n // 50)
        # Per-sample flags as Python lists, computed once: the loop below is Python-bound (mj_step aside).
        move_of, suction = tr.move_index.tolist(), tr.suction.tolist()
        release = tr.phase == Phase.RELEASE_DWELL
        completes = np.append(False, release[:-1] & ~release[1:]).tolist()  # first sample after a release dwell
        fault = None
        k = 0
        for k in range(1, n):
            mv = move_of[k]
            want = suction[k]
            if want != cup.on:
                if not want and cup.attached is not None:
                    # Feedback as last read, i.e. just before the suction is switched off.
                    _, digin, ain0 = self.trace[-1]
                    self.events.append(FeedbackEvent(float(d.time), "release", mv, cup.attached, int(digin), ain0))
                cup.command(want)
            cup.update()
            servo.cycle(self.commands[k], tr.qdd[k], partial(self._inject_drop, mv) if k == self.drop_k else None)
            fb = self.after_cycle()
            err = np.abs(self.joints[-1][1] - tr.q[k]).max()
            if err > self.max_err:
                self.max_err = float(err)
            if completes[k]:
                self.moves_completed += 1
            check.track_grasp(k, mv)
            fault = check.after_sample(k, mv, fb)
            if fault is not None:
                break
            if self.progress is not None and k % report_every == 0:
                self.progress(k / (n - 1), f"move {max(mv, 0) + 1}/{len(moves)}")
        self.ref_chunks.append((tr.q[:k + 1], tr.qd[:k + 1], tr.qdd[:k + 1]))
        return fault

    def _inject_drop(self, mv: int) -> None:
        lost = self.cup.lose_block()
        self.drop_time = float(self.scene.data.time)
        self.events.append(FeedbackEvent(self.drop_time, "drop_injected", mv, -1 if lost is None else lost, 0, 0.0))

    # ------------------------------------------------------------------------------------------ 2. halt / settle

    def _stream(self, qs: FloatArray, vs: FloatArray, accs: FloatArray) -> None:
        """Stream reference samples (q, qd, qdd) through the servo, as the plan's."""
        self.ref_chunks.append((qs, vs, accs))
        for q_k, v_k, a_k in zip(qs, vs, accs, strict=True):
            self.servo.cycle(self.servo.command(q_k, v_k), a_k)
            self.after_cycle()

    def halt(self, fault: Fault, profile: HaltProfile) -> FloatArray:
        """Halt like the lab program: stop (from the reference state: no jump), suction off, vent, go home.
        Returns the pose to hold afterwards (home)."""
        tr, st, cup, dt, speed = self.tr, self.plan.station, self.cup, self.servo.period_s, self.cfg.halt_speed_scale
        k = fault.k
        self.halt_start = len(self.joints)
        cup.grasp_enabled = False
        self._stream(*profile(tr.q[k], tr.qd[k], tr.qdd[k], st, speed, dt, None))
        cup.command(False)
        q_rest = self.servo.last_command.copy()
        z = np.zeros(N_JOINTS)
        n_vent = round(0.2 / dt)  # let the vacuum vent before moving on
        self._stream(np.tile(q_rest, (n_vent, 1)), np.zeros((n_vent, N_JOINTS)), np.zeros((n_vent, N_JOINTS)))
        self._stream(*profile(q_rest, z, z, st, speed, dt, st.q_home_array))
        return st.q_home_array

    def settle(self, q_final_ref: FloatArray) -> None:
        """Hold ``q_final_ref`` for ``settle_s`` (blocks settle, the servo converges)."""
        n = round(self.cfg.settle_s / self.servo.period_s)
        z = np.zeros((n, N_JOINTS))
        self.ref_chunks.append((np.tile(q_final_ref, (n, 1)), z, z))
        for _ in range(n):
            self.servo.hold(q_final_ref)
            self.after_cycle()

    # ------------------------------------------------------------------------------------------ 3. verification

    def joint_trace(self, settle_start: int) -> JointTrace:
        t, q, qd = zip(*self.joints, strict=True)
        q_ref, qd_ref, qdd_ref = (np.vstack(c) for c in zip(*self.ref_chunks, strict=True))
        return JointTrace(t=np.array(t), q_ref=q_ref, qd_ref=qd_ref, qdd_ref=qdd_ref, q=np.array(q),
                          qd=np.array(qd), halt_start=self.halt_start, settle_start=settle_start)

    def result(self, fault: Fault | None, wall: float, settle_start: int) -> SimResult:
        """The outcome: final block positions, arm and suction state, and the status the checks give."""
        cfg, moves, scene = self.cfg, self.plan.moves, self.scene
        final = locate_blocks(scene, slot_centers(self.plan.station), cfg.place_tolerance_m)
        displaced: list[DisplacedBlock] = []
        mv = block = fault_tower = None
        latency = None
        if fault is not None:
            mv, block = fault.move, fault.block
            latency = None if self.drop_time is None else fault.t - self.drop_time
            status, code = "halted", SuctionFaultError.exit_code
            displaced = displaced_blocks(self.plan, scene, fault.resting, cfg.knock_tolerance_m,
                                         cfg.place_tolerance_m)
            error: str | None = fault.message + ("; final check: " + "; ".join(d.describe() for d in displaced)
                                                 if displaced else "")
            fault_tower = moves[mv].from_tower  # where the block was (missing) or came from (dropped)
        else:
            error = final_check(final, moves[-1].to_tower, cfg.place_tolerance_m)
            status, code = ("solved", 0) if error is None else ("failed", SimulationError.exit_code)
        return SimResult(
            status=status, exit_code=code, error=error, moves_completed=self.moves_completed,
            moves_total=len(moves), final_blocks=final, suction_on_at_end=self.cup.on,
            at_home_at_end=at_home(scene, cfg.home_tolerance_rad), sim_time_s=float(scene.data.time),
            wall_time_s=wall, max_tracking_error_rad=self.max_err, feedback_events=tuple(self.events),
            fault_move=mv, fault_block=block, fault_tower=fault_tower, detection_latency_s=latency,
            displaced_blocks=tuple(displaced), warnings=warning_counts(scene.data),
            feedback_trace=np.array(self.trace, dtype=float).reshape(-1, 3),
            joint_trace=self.joint_trace(settle_start),
        )

def run_plan(plan: Plan, faults: Faults | None = None, config: SimConfig | None = None,
             frames: FrameSink | None = None, progress: ProgressFn | None = None,
             scene: TaskScene | None = None, realtime: bool = False, halt: HaltProfile | None = None) -> SimResult:
    """Execute ``plan`` in MuJoCo like the lab program: stream, operate suction, check feedback, halt on faults.

    Each control cycle (``1 / rate_hz`` [s], 4 physics steps at 125 Hz / 2 ms) commands the next trajectory
    sample with velocity and acceleration feed-forward (:mod:`ur3hanoi.sim.servo`), so the servo force is
    ``kp (q_ref - q) + kv (qd_ref - qd) + M(q) qdd_ref``; then reads ``gripper_input``. A
    block must be held at the end of every GRASP_DWELL and in every cycle of a carrying phase; otherwise the arm
    decelerates to rest (Ruckig, from the reference state), the suction is turned off and the arm returns home
    (Ruckig), and
    :class:`~ur3hanoi.errors.SuctionFaultError` is raised with the "halted" :class:`SimResult` as ``.result``.

    Args:
        plan: the motion plan (its start tower and block count define the scene unless ``scene`` is given).
        faults: injected faults (0-based).
        frames: called at ``frames.fps`` with the state (offscreen rendering, viewer).
        progress: called with (fraction done, label) about 50 times per run.
        scene: a pre-built scene (must match the plan).
        realtime: pace the loop to wall-clock time (for the interactive viewer).
        halt: the motion profile of a halt (None: :data:`~ur3hanoi.sim.halt.DEFAULT_HALT_PROFILE`, jerk-limited
            Ruckig; see :class:`~ur3hanoi.sim.halt.HaltProfile`).

    Returns:
        the result, "solved" or "failed" (the final positions do not match the plan).

    Raises:
        SuctionFaultError: a suction check failed; the arm was halted and returned home (``.result``).
        SimulationError: the faults do not fit the plan, or the scene cannot run it.
    """
    faults = faults if faults is not None else Faults()
    cfg = config if config is not None else SimConfig()
    start, n_blocks = _validate(plan, faults)
    if scene is None:
        scene = build_task_scene(plan.station, start, n_blocks, faults.remove_block, cfg.scene)
    run = _Run(plan, scene, faults, cfg, frames, progress, realtime)
    tr: Trajectory = plan.trajectory

    fault = run.stream_plan()
    if fault is not None:
        q_final_ref = run.halt(fault, halt if halt is not None else DEFAULT_HALT_PROFILE)
    else:
        q_final_ref = tr.q[-1]
        run.cup.command(bool(tr.suction[-1]))
    settle_start = len(run.joints)
    run.settle(q_final_ref)
    if progress is not None:
        progress(1.0, "done")
    wall = time.perf_counter() - run.wall0

    result = run.result(fault, wall, settle_start)
    if fault is not None:
        raise SuctionFaultError(result.error or fault.message, result)
    return result
