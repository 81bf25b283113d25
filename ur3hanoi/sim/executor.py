"""Execute a plan in MuJoCo like the lab program: stream the reference, operate the suction, check the feedback,
halt on a fault, and verify the final block positions from the simulation state.

:func:`run_plan` runs four steps, each a method of one run (:class:`_Run`):

1. **streaming** (:meth:`_Run.stream_plan`): every control cycle commands the next trajectory sample with velocity
   feed-forward, switches the suction at the plan's events and reads ``gripper_input``;
2. **suction check** (:meth:`_Run.check_suction`, every cycle of step 1): a block must be held at the end of every
   GRASP_DWELL and in every cycle of a carrying phase, else streaming stops with a fault;
3. **halt** (:meth:`_Run.halt`, after a fault): decelerate to rest from the reference state (jerk-limited, no
   jump: :mod:`ur3hanoi.sim.halt`), suction off, vent, return home; then, as without a fault, hold the final
   pose while the blocks settle (:meth:`_Run.settle`);
4. **final verification** (:meth:`_Run.result`): where every block is, whether the arm is home and the suction off.

After a halt :func:`run_plan` raises :class:`ur3hanoi.errors.SuctionFaultError` carrying the :class:`SimResult`
(``error.result``): the lab program's halt condition is an error for the caller, with the full outcome attached.

Numbering: internally 0-based (towers, heights, blocks, moves); messages and JSON are 1-based like the lab.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Protocol

import mujoco
import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError, SuctionFaultError
from ur3hanoi.hanoi import block_colour
from ur3hanoi.plan import Phase, Plan, Trajectory
from ur3hanoi.robot.model import JOINT_NAMES, N_JOINTS
from ur3hanoi.sim.diagnosis import displaced_blocks, missed_grasp, missing_block
from ur3hanoi.sim.halt import DEFAULT_HALT_PROFILE, HaltProfile
from ur3hanoi.sim.result import DisplacedBlock, FeedbackEvent, FinalBlock, JointTrace, SimResult
from ur3hanoi.sim.scene import SceneConfig, TaskScene, build_task_scene, slot_centers, slot_of, warning_counts
from ur3hanoi.sim.suction import GripperInput, SuctionConfig, SuctionCup


@dataclass(frozen=True)
class Faults:
    """Injected faults (0-based). ``remove_block``: height left empty at spawn; ``drop_during_move``: index of
    the move during whose carry the suction loses its block (at the middle sample of its CARRY phase)."""

    remove_block: int | None = None
    drop_during_move: int | None = None


@dataclass(frozen=True)
class SimConfig:
    """Executor settings.

    Attributes:
        scene, suction: see :class:`SceneConfig`, :class:`SuctionConfig`.
        seed: seeds the feedback noise.
        place_tolerance: a block is "at" a slot when its centre is within this distance [m] of the slot's centre.
        home_tolerance: "at home" when every joint is within this angle [rad] of the home pose.
        halt_speed: fraction of the joint limits used to stop and to return home after a fault.
        settle_s: time [s] simulated at rest after the last sample (blocks settle, the servo converges).
        knock_tolerance: after a halt, a block that rested when the fault was detected and has since moved
            farther than this [m] was knocked (e.g. by the dropped block) and is reported.
        accel_feedforward: add the arm's own inertia times the reference acceleration, ``M(q) qdd_ref / kp``, to
            the servo command (the UR controller moves on a model of its arm; velocity feed-forward alone left the
            cup ~0.2 mm below the contact pose at the end of a place, pressing the block into the stack).
    """

    scene: SceneConfig = field(default_factory=SceneConfig)
    suction: SuctionConfig = field(default_factory=SuctionConfig)
    seed: int = 0
    place_tolerance: float = 0.005
    home_tolerance: float = 0.01
    halt_speed: float = 0.5
    settle_s: float = 0.3
    knock_tolerance: float = 0.001
    accel_feedforward: bool = True


class FrameSink(Protocol):
    """Receives the simulation state at ``fps`` for rendering or viewing."""

    fps: float

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None: ...


ProgressFn = Callable[[float, str], None]


@dataclass(frozen=True)
class _Fault:
    """A failed suction check: at plan sample ``k``, sim time ``t`` [s] (0-based move and block).

    ``resting`` holds the position [m, world] of every block that rested in the scene when the fault was detected
    (all but the one lost from the cup), to find the blocks knocked out of place afterwards.
    """

    move: int
    block: int
    message: str
    t: float
    k: int
    resting: dict[int, FloatArray] = field(default_factory=dict)


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


class _Run:
    """One execution of a plan in a task scene: the state the steps of :func:`run_plan` share."""

    def __init__(self, plan: Plan, scene: TaskScene, faults: Faults, cfg: SimConfig, frames: FrameSink | None,
                 progress: ProgressFn | None, realtime: bool) -> None:
        self.plan, self.scene, self.cfg = plan, scene, cfg
        self.frames, self.progress, self.realtime = frames, progress, realtime
        m, d = self.m, self.d = scene.model, scene.data
        tr = self.tr = plan.trajectory
        self.dt_ctrl = 1.0 / tr.rate_hz
        self.nsub = round(self.dt_ctrl / m.opt.timestep)
        if self.nsub < 1 or abs(self.nsub * m.opt.timestep - self.dt_ctrl) > 1e-9:
            raise SimulationError(f"control period {self.dt_ctrl} s is not a multiple of the physics step "
                                  f"{m.opt.timestep} s")

        # Start at rest on the first sample.
        d.qpos[scene.arm_qadr] = tr.q[0]
        d.qvel[scene.arm_dadr] = 0.0
        mujoco.mj_forward(m, d)
        self.act_ids = np.array([m.actuator(j.removesuffix("_joint")).id for j in JOINT_NAMES])
        kp = m.actuator_gainprm[self.act_ids, 0]
        kv = -m.actuator_biasprm[self.act_ids, 2]
        self.ff = kv / kp  # feed-forward velocity gain [s]
        # During cycle k the servo command moves linearly from sample k-1 to sample k, like a UR controller
        # interpolating its servo targets: each physics step holds the mean of that line over the step. A zero-order
        # hold of the end sample would lead the trajectory by a full cycle (measured: 0.67 deg error at the wrist
        # instead of 0.13 deg); holding the cycle's mean lags it by half a cycle, which the stiff servo
        # (ur3hanoi.sim.model.DRIVES) paid for with kp * v * 4 ms of torque: the wrists saturated at 12 N m
        # returning home after a halt. Precomputed: the loop is Python-bound.
        self.servo = tr.q + tr.qd * self.ff  # (N, 6)
        self._ramp = (np.arange(self.nsub) + 0.5) / self.nsub  # each physics step's mean point on the cycle's line
        d.ctrl[self.act_ids] = self.servo[0]
        # Acceleration feed-forward per cycle (the mean of samples k-1 and k), or None (SimConfig.accel_feedforward).
        self.kp = kp
        self.acc: FloatArray | None = None
        if cfg.accel_feedforward:
            self.acc = tr.qdd.copy()
            self.acc[1:] = 0.5 * (tr.qdd[1:] + tr.qdd[:-1])
        self._acc_vec, self._acc_res = np.zeros(m.nv), np.zeros(m.nv)
        self._last_acc = np.zeros(N_JOINTS)  # reference acceleration of the last sample streamed [rad/s^2]

        self.cup = SuctionCup(scene, cfg.suction, seed=cfg.seed)
        self.events: list[FeedbackEvent] = []
        self.drop_k = -1
        if faults.drop_during_move is not None:
            ks = np.flatnonzero((tr.move_index == faults.drop_during_move) & (tr.phase == Phase.CARRY))
            if ks.size == 0:
                raise SimulationError(f"move {faults.drop_during_move + 1} has no CARRY phase to drop the block in")
            self.drop_k = int(ks[ks.size // 2])
        self.drop_time: float | None = None
        # Per move: the closest the cup (suction point) came to the grasp point of the block to pick during the
        # grasp dwell [m], for the message when nothing was grasped.
        self.closest_grasp: dict[int, float] = {}
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

    def step_cycle(self, cmd_from: FloatArray, cmd_to: FloatArray, split_after: int = 0,
                   on_split: Callable[[], None] | None = None, acc_k: FloatArray | None = None) -> GripperInput:
        """Move the servo command linearly from ``cmd_from`` to ``cmd_to`` over one control cycle (plus the
        acceleration feed-forward of ``acc_k`` [rad/s^2], if given; ``on_split`` runs after ``split_after`` physics
        steps), render, pace, record the joints, and read ``gripper_input`` like the driver does every cycle."""
        m, d = self.m, self.d
        offset = 0.0
        if acc_k is not None:  # + M(q) qdd / kp: the joint-space inertia (armature included) at the current pose
            self._acc_vec[self.scene.arm_dadr] = acc_k
            mujoco.mj_mulM(m, d, self._acc_res, self._acc_vec)
            offset = self._acc_res[self.scene.arm_dadr] / self.kp
        delta = cmd_to - cmd_from
        for j, r in enumerate(self._ramp):
            d.ctrl[self.act_ids] = cmd_from + r * delta + offset
            mujoco.mj_step(m, d)
            if j + 1 == split_after and on_split is not None:
                on_split()
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

    def stream_plan(self) -> _Fault | None:
        """Stream the plan's samples 1.. until the end or the first failed suction check (returned)."""
        tr, d, cup = self.tr, self.d, self.cup
        moves = self.plan.moves
        n = len(tr.t)
        report_every = max(1, n // 50)
        # Per-sample flags as Python lists, computed once: the loop below is Python-bound (mj_step aside).
        move_of, suction = tr.move_index.tolist(), tr.suction.tolist()
        release = tr.phase == Phase.RELEASE_DWELL
        completes = np.append(False, release[:-1] & ~release[1:]).tolist()  # first sample after a release dwell
        flags = self._check_flags()
        grasping = (tr.phase == Phase.GRASP_DWELL).tolist()
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
            if k == self.drop_k:
                fb = self.step_cycle(self.servo[k - 1], self.servo[k], split_after=1,
                                     on_split=partial(self._inject_drop, mv),
                                     acc_k=None if self.acc is None else self.acc[k])
            else:
                fb = self.step_cycle(self.servo[k - 1], self.servo[k],
                                     acc_k=None if self.acc is None else self.acc[k])
            err = np.abs(self.joints[-1][1] - tr.q[k]).max()
            if err > self.max_err:
                self.max_err = float(err)
            if completes[k]:
                self.moves_completed += 1
            if grasping[k] and cup.attached is None:
                self._track_grasp(mv)
            fault = self.check_suction(k, mv, fb, flags)
            if fault is not None:
                break
            if self.progress is not None and k % report_every == 0:
                self.progress(k / (n - 1), f"move {max(mv, 0) + 1}/{len(moves)}")
        self.ref_chunks.append((tr.q[:k + 1], tr.qd[:k + 1], tr.qdd[:k + 1]))
        self._last_acc = tr.qdd[k]
        return fault

    def _track_grasp(self, mv: int) -> None:
        """Update the closest approach of the cup to the grasp point of move ``mv``'s block (see the grasp rule,
        :class:`~ur3hanoi.sim.SuctionConfig.grasp_radius`)."""
        block = self.plan.moves[mv].block
        if block in self.scene.block_body:
            p_cup = self.d.site_xpos[self.scene.site_id]
            dist = float(np.linalg.norm(self.cup.expected_suction_point(block) - p_cup))
            self.closest_grasp[mv] = min(dist, self.closest_grasp.get(mv, math.inf))

    def _inject_drop(self, mv: int) -> None:
        lost = self.cup.lose_block()
        self.drop_time = float(self.d.time)
        self.events.append(FeedbackEvent(self.drop_time, "drop_injected", mv, -1 if lost is None else lost, 0, 0.0))

    # ------------------------------------------------------------------------------------------ 2. suction check

    def _check_flags(self) -> tuple[list[bool], list[bool]]:
        """Per sample: the last sample of a grasp dwell (a block must be held), a carrying phase (held every cycle)."""
        tr = self.tr
        grasp = tr.phase == Phase.GRASP_DWELL
        dwell_ends = (grasp & ~np.append(grasp[1:], False)).tolist()
        carrying = np.isin(tr.phase, [p for p in Phase if p.carrying]).tolist()
        return dwell_ends, carrying

    def check_suction(self, k: int, mv: int, fb: GripperInput,
                      flags: tuple[list[bool], list[bool]]) -> _Fault | None:
        """The lab program's check after sample ``k``: a block held where one must be, else the fault."""
        dwell_ends, carrying = flags
        dwell_end = dwell_ends[k]
        moves = self.plan.moves
        if (dwell_end or carrying[k]) and not fb.held:
            move = moves[mv]
            kind = "missing" if dwell_end else "dropped"
            self.events.append(FeedbackEvent(fb.t, kind, mv, move.block, fb.digin, fb.ain0))
            sensed = f"(DIGIN={fb.digin}, AIN0={fb.ain0:.2f} V)"
            block = move.block
            if kind == "dropped":
                what = (f"{block_colour(block)} block {block + 1} was dropped while carrying it from tower "
                        f"{move.from_tower + 1} to tower {move.to_tower + 1} {sensed}")
            else:
                missed = missed_grasp(self.plan, mv, self.closest_grasp.get(mv), self.cfg.suction.grasp_radius)
                block, what = missing_block(self.plan, self.scene, mv, sensed, self.cfg.place_tolerance, missed)
            msg = f"suction fault in move {mv + 1}/{len(moves)}: {what}; halted, suction off, arm returned home"
            resting = {b: self.scene.block_pos(b) for b in self.scene.block_body if kind == "missing" or b != block}
            return _Fault(mv, block, msg, fb.t, k, resting)
        if dwell_end:
            cup = self.cup
            self.events.append(FeedbackEvent(fb.t, "grasp", mv, cup.attached if cup.attached is not None else -1,
                                             fb.digin, fb.ain0))
        return None

    # ------------------------------------------------------------------------------------------ 3. halt / settle

    def _stream(self, qs: FloatArray, vs: FloatArray, accs: FloatArray, last: FloatArray) -> FloatArray:
        """Stream reference samples (with feed-forward, interpolated as for the plan) from the command ``last``;
        returns the last command."""
        self.ref_chunks.append((qs, vs, accs))
        for q_k, v_k, a_k in zip(qs, vs, accs, strict=True):
            cmd = q_k + self.ff * v_k
            acc = None if self.acc is None else 0.5 * (self._last_acc + a_k)
            self.step_cycle(last, cmd, acc_k=acc)  # as for the plan
            last, self._last_acc = cmd, a_k
        return last

    def halt(self, fault: _Fault, profile: HaltProfile) -> FloatArray:
        """Halt like the lab program: stop (from the reference state: no jump), suction off, vent, go home.
        Returns the pose to hold afterwards (home)."""
        tr, st, cup, dt = self.tr, self.plan.station, self.cup, self.dt_ctrl
        k = fault.k
        self.halt_start = len(self.joints)
        cup.grasp_enabled = False
        last = self._stream(*profile(tr.q[k], tr.qd[k], tr.qdd[k], st, self.cfg.halt_speed, dt, None),
                            self.servo[k])
        cup.command(False)
        q_rest = last.copy()
        z = np.zeros(N_JOINTS)
        n_vent = round(0.2 / dt)  # let the vacuum vent before moving on
        last = self._stream(np.tile(q_rest, (n_vent, 1)), np.zeros((n_vent, N_JOINTS)), np.zeros((n_vent, N_JOINTS)),
                            last)
        self._stream(*profile(q_rest, z, z, st, self.cfg.halt_speed, dt, st.q_home_array), last)
        return st.q_home_array

    def settle(self, q_final_ref: FloatArray) -> None:
        """Hold ``q_final_ref`` for ``settle_s`` (blocks settle, the servo converges)."""
        n = round(self.cfg.settle_s / self.dt_ctrl)
        z = np.zeros((n, N_JOINTS))
        self.ref_chunks.append((np.tile(q_final_ref, (n, 1)), z, z))
        for _ in range(n):
            self.step_cycle(q_final_ref, q_final_ref)

    # ------------------------------------------------------------------------------------------ 4. verification

    def final_blocks(self) -> list[FinalBlock]:
        """Where every block is, read from the simulation state."""
        final = []
        centers = slot_centers(self.plan.station)
        for b in sorted(self.scene.block_body):
            xyz = self.scene.block_pos(b)
            slot = slot_of(centers, xyz, self.cfg.place_tolerance)
            final.append(FinalBlock(b, None if slot is None else slot[0], None if slot is None else slot[1],
                                    (float(xyz[0]), float(xyz[1]), float(xyz[2]))))
        return final

    def joint_trace(self, settle_start: int) -> JointTrace:
        t, q, qd = zip(*self.joints, strict=True)
        q_ref, qd_ref, qdd_ref = (np.vstack(c) for c in zip(*self.ref_chunks, strict=True))
        return JointTrace(t=np.array(t), q_ref=q_ref, qd_ref=qd_ref, qdd_ref=qdd_ref, q=np.array(q),
                          qd=np.array(qd), halt_start=self.halt_start, settle_start=settle_start)

    def result(self, fault: _Fault | None, wall: float, settle_start: int) -> SimResult:
        """The outcome: final block positions, arm and suction state, and the status the checks give."""
        cfg, st, moves, cup = self.cfg, self.plan.station, self.plan.moves, self.cup
        final = self.final_blocks()
        displaced: list[DisplacedBlock] = []
        at_home = bool(np.max(np.abs(self.scene.arm_q() - st.q_home_array)) <= cfg.home_tolerance)
        end_tower = moves[-1].to_tower if fault is None else None
        mv: int | None
        block: int | None
        if fault is not None:
            mv, block, msg, t_det = fault.move, fault.block, fault.message, fault.t
            latency = None if self.drop_time is None else t_det - self.drop_time
            status, code, error = "halted", SuctionFaultError.exit_code, msg
            displaced = displaced_blocks(self.plan, self.scene, fault.resting, cfg.knock_tolerance,
                                         cfg.place_tolerance)
            if displaced:
                error += "; final check: " + "; ".join(d.describe() for d in displaced)
            fault_tower = moves[mv].from_tower  # where the block was (missing) or came from (dropped)
        else:
            mv = block = None
            latency = None
            fault_tower = None
            wrong = [fb for fb in final if (fb.tower, fb.height) != (end_tower, fb.block)]
            if wrong:
                status, code = "failed", SimulationError.exit_code
                error = "final state check failed: " + "; ".join(
                    f"{block_colour(fb.block)} block {fb.block + 1} at {np.round(fb.xyz, 4).tolist()} is not within "
                    f"{cfg.place_tolerance * 1e3:.0f} mm of tower {end_tower + 1} height {fb.block + 1}"  # type: ignore[operator]
                    for fb in wrong)
            else:
                status, code, error = "solved", 0, None
        return SimResult(
            status=status, exit_code=code, error=error, moves_completed=self.moves_completed,
            moves_total=len(moves), final_blocks=tuple(final), suction_on_at_end=cup.on, at_home_at_end=at_home,
            sim_time_s=float(self.d.time), wall_time_s=wall, max_tracking_error_rad=self.max_err,
            feedback_events=tuple(self.events), fault_move=mv, fault_block=block, fault_tower=fault_tower,
            detection_latency_s=latency, displaced_blocks=tuple(displaced), warnings=warning_counts(self.d),
            feedback_trace=np.array(self.trace, dtype=float).reshape(-1, 3),
            joint_trace=self.joint_trace(settle_start),
        )


def run_plan(plan: Plan, faults: Faults | None = None, config: SimConfig | None = None,
             frames: FrameSink | None = None, progress: ProgressFn | None = None,
             scene: TaskScene | None = None, realtime: bool = False, halt: HaltProfile | None = None) -> SimResult:
    """Execute ``plan`` in MuJoCo like the lab program: stream, operate suction, check feedback, halt on faults.

    Each control cycle (``1 / rate_hz`` [s], 4 physics steps at 125 Hz / 2 ms) commands the next trajectory
    sample with velocity and acceleration feed-forward, ``ctrl = q_ref + (kv/kp) * qd_ref + M(q) qdd_ref / kp``,
    so the servo force is ``kp (q_ref - q) + kv (qd_ref - qd) + M(q) qdd_ref``; then reads ``gripper_input``. A
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
