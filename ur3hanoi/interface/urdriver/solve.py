"""The Ruckig plan on the official UR driver, with the lab's suction checks: ``ros-solve --driver ur`` and
``ros2-solve --driver ur``, whatever the middleware.

:func:`run_driver_solve` executes a :class:`ur3hanoi.plan.Plan` through a
:class:`~ur3hanoi.interface.urdriver.client.DriverTransport`:

0. **Vacuum.** The calibration's vacuum generator output (``io.vacuum_generator_output``; ENME480's UR3e cells:
   ``set_io`` pin 12) is switched on before anything moves, as the course's bridge does; every output the suction
   uses (the cup's, then the generator's) is switched off at the end and on every other way out: a halt, an error,
   Ctrl-C or SIGTERM (which ur3hanoi raises as an interrupt), after the running goal is canceled.
1. **Start.** The arm's joint states (by name) are compared with where the plan starts: within
   ``start_tolerance_rad`` it starts; farther, it is first brought there by a slow goal (``approach_speed`` of the
   limits; the line says so), or the solve refuses with the distance (``far_start="refuse"``). Never a jump.
2. **Motion goals.** Each stretch of the plan between two suction dwells is one ``FollowJointTrajectory`` goal with
   the plan's own samples (:mod:`~ur3hanoi.interface.urdriver.plan_goals`), sent when the previous one succeeded. The
   client waits with its own timeout: the goal's duration plus ``goal_margin_s`` of *trajectory* time, which advances
   with the speed scaling the driver reports (a slider at 50 % doubles the wall time allowed; paused, it waits).
3. **Suction.** At a grasp dwell ``set_io`` switches the calibration's output on, then the vacuum switch input
   must read 1 within ``grasp_timeout_s`` and the dwell lasts at least as planned; at a release dwell the output goes
   off for the planned dwell (and until the switch clears, at most ``release_timeout_s``). While a block is carried
   (lift, carry, place) every ``io_states`` is checked; the first without the block cancels the running goal.
4. **Halt** (a block missing at a grasp or dropped in a carry): cancel, suction off, the arm waits at rest, then a
   slow goal home; :class:`~ur3hanoi.errors.SuctionFaultError` (exit 3), one line as the lab program's. A grasp
   whose vacuum sensor reads the calibration's no-vacuum level (nearer its ``ain0_off`` than its ``ain0_free``)
   although the cup's output is on is a cell without vacuum, not a missing block: the line says so and names the
   generator's pin (or that the calibration names none).
5. **Errors.** A goal the controller rejects or aborts: suction off,
   :class:`~ur3hanoi.interface.urdriver.client.DriverGoalError` (exit 2) with the driver's code and error string; a
   goal past its timeout: canceled, suction off,
   :class:`~ur3hanoi.errors.DriverError`; joint states that stop: the same.
   **The External Control program** (the driver's latched ``robot_program_running``): stopped before the start, the
   solve refuses (:class:`~ur3hanoi.errors.DriverError`, "start the External Control program on the pendant");
   stopped mid-solve (the controller stops with it: ROS 2 aborts the goal, ROS 1 preempts it), suction off and
   :class:`~ur3hanoi.errors.ProgramStoppedError` (exit 3): the arm stopped where it was.
6. **The path.** Every joint state received from the plan's start to its end is recorded by the transport
   (:class:`~ur3hanoi.interface.urdriver.joint_record.JointRecord`); after a solve, the largest distance of the
   executed suction point from the plan's path (each joint state against its goal's stretch), overall and on the
   vertical legs
   (:func:`~ur3hanoi.interface.urdriver.path_deviation.path_deviation`), is in the result.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import DriverError, ProgramStoppedError, SuctionFaultError
from ur3hanoi.hanoi import Move, block_colour
from ur3hanoi.interface.common.moves import describe_move
from ur3hanoi.interface.urdriver.client import DriverGoalError, DriverTransport, GoalHandle, GoalResult
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, FUN_SET_DIGITAL_OUT, ErrorCode
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal
from ur3hanoi.interface.urdriver.path_deviation import PathDeviation, path_deviation, stretch_windows
from ur3hanoi.interface.urdriver.plan_goals import Stretch, move_goal, plan_stretches
from ur3hanoi.interface.urdriver.vacuum import feedback_text, no_vacuum, vacuum_hint
from ur3hanoi.plan import Plan
from ur3hanoi.station.suction_wiring import GENERATOR_KEY, SuctionWiring, output_name


@dataclass(frozen=True)
class DriverSolveConfig:
    """How the client drives (times [s], angles [rad]; see the module docstring)."""

    grasp_timeout_s: float = 1.0
    release_timeout_s: float = 0.5
    start_tolerance_rad: float = 0.01
    far_start: Literal["approach", "refuse"] = "approach"
    approach_speed: float = 0.25
    home_speed: float = 0.25
    goal_margin_s: float = 2.0
    state_timeout_s: float = 2.0
    rest_timeout_s: float = 3.0
    poll_s: float = 0.002
    program_wait_s: float = 0.5
    cancel_wait_s: float = 5.0  # a goal sent, not yet accepted, is canceled on acceptance: wait for it


@dataclass(frozen=True)
class DriverSolveResult:
    """A completed solve: the moves, the goals sent, the wall times [s] of the whole, of the approach to the plan's
    start and of the plan's execution (to compare with the plan's own cycle time [s]), and how closely the executed
    suction point followed the plan's path (None: no joint state was recorded)."""

    moves: tuple[Move, ...]
    goals: int
    wall_time_s: float
    approach_s: float
    executed_s: float
    plan_duration_s: float
    path: PathDeviation | None = None


class _HaltError(Exception):
    def __init__(self, kind: str) -> None:
        super().__init__(kind)
        self.kind = kind


class _Solve:
    """One run of :func:`run_driver_solve`: the state its steps share."""

    def __init__(self, transport: DriverTransport, plan: Plan, wiring: SuctionWiring, cfg: DriverSolveConfig,
                 say: Callable[[str], None]) -> None:
        self.tr, self.plan, self.wiring, self.cfg, self.say = transport, plan, wiring, cfg, say
        self.goals = 0
        self.n_goals = 0
        self.active: GoalHandle | None = None
        self.last: dict[int, bool | None] = {}  # each output's last state set_io confirmed (None: asked, unanswered)

    # ------------------------------------------------------------------------------------------ reading
    def held(self) -> bool:
        io = self.tr.latest().io
        return io is not None and io.digital_in[self.wiring.switch_input]

    def q(self) -> FloatArray:
        st = self.tr.latest()
        if st.q is None:
            raise DriverError(f"no joint states from the driver on {self.tr.where}")
        return st.q

    def sleep(self, seconds: float, until: Callable[[], bool] = lambda: False) -> bool:
        """Wait ``seconds`` (watching the transport) or until ``until()``: True when it came true."""
        end = self.tr.now() + seconds
        while True:
            if until():
                return True
            left = end - self.tr.now()
            if left <= 0.0:
                return False
            self.tr.wait(min(self.cfg.poll_s, left))

    # ------------------------------------------------------------------------------------------ goals
    def run_goal(self, goal: TrajectoryGoal, what: str, carrying: bool = False) -> None:
        """Send ``goal`` and wait for its success, watching the suction while ``carrying``."""
        cfg, tr = self.cfg, self.tr
        self.goals += 1
        label = f"goal {self.goals}" + (f"/{self.n_goals}" if self.goals <= self.n_goals else "") + f" ({what})"
        handle = self.active = tr.send_goal(goal)
        allowed = goal.points[-1].time_from_start_s + cfg.goal_margin_s if goal.points else cfg.goal_margin_s
        tau, last = 0.0, self.tr.now()
        while not handle.done():
            tr.wait(cfg.poll_s)
            now, st = self.tr.now(), tr.latest()
            if st.program_running is False:  # the controller ends the goal too: its result says how
                self.sleep(cfg.program_wait_s, handle.done)
                raise self.program_stopped(label, handle.result() if handle.done() else None)
            tau += (now - last) * (1.0 if st.speed_scaling is None else st.speed_scaling)
            last = now
            if carrying and not self.held():
                self._cancel(handle)
                raise _HaltError("dropped")
            if now - st.t_q > cfg.state_timeout_s:
                self._cancel(handle)
                self.suction(False)
                raise DriverError(f"joint states stopped: none from the driver on {tr.where} for "
                                  f"{now - st.t_q:.1f} s during {label}; is the driver still running?")
            if tau > allowed:
                self._cancel(handle)
                self.suction(False)
                raise DriverError(f"{label} did not finish within {allowed:.1f} s of trajectory time (the speed "
                                  f"scaling the driver reports counted): canceled, suction off")
        self.active = None
        result = handle.result()
        # The controller's end and the program's topic travel apart: a goal ended as a stop ends it waits for both.
        if result.status != "succeeded" and (result.status == "preempted" or result.code == ErrorCode.INVALID_GOAL) \
                and self.sleep(cfg.program_wait_s, lambda: tr.latest().program_running is False):
            raise self.program_stopped(label, result)
        if result.status != "succeeded":
            self.suction(False)
            verb = "rejected" if result.status == "rejected" else "ended"
            raise DriverGoalError(f"the driver's controller {verb} {label}: {result.describe()}; suction off, "
                                  "the solve stops", result)

    def check_program(self) -> None:
        """Refuse to start while the External Control program is stopped (its state is latched: it arrives with the
        connection; a driver that never says is let through)."""
        self.sleep(self.cfg.program_wait_s, lambda: self.tr.latest().program_running is not None)
        if self.tr.latest().program_running is False:
            raise DriverError(f"the robot program is not running (robot_program_running is false on {self.tr.where}):"
                              " the driver's trajectory controller refuses every goal until it runs; start the "
                              "External Control program on the pendant")

    def program_stopped(self, label: str, result: GoalResult | None) -> ProgramStoppedError:
        """Suction off; the error of a program that stopped during ``label``."""
        self.suction(False)
        how = "" if result is None else f"; the controller: {result.describe()}"
        return ProgramStoppedError(
            f"the External Control program stopped on the robot during {label} (robot_program_running false{how}):"
            " the arm stopped where it was, suction off; check the blocks, start the program on the pendant and "
            "run again")

    def _cancel(self, handle: GoalHandle) -> None:
        if not handle.done():
            handle.cancel()
            self.sleep(self.cfg.cancel_wait_s, handle.done)

    def output(self, pin: int, on: bool, key: str) -> None:
        """``set_io`` digital output ``pin`` (the calibration's ``io.<key>``) on or off."""
        self.last[pin] = None
        if self.tr.set_io(FUN_SET_DIGITAL_OUT, pin, 1.0 if on else 0.0):
            self.last[pin] = on
        else:
            raise DriverError(f"set_io(fun={FUN_SET_DIGITAL_OUT}, pin={pin}, state={1 if on else 0}) answered "
                              f"success = false on {self.tr.where}: is the pin right (calibration io.{key}) and the "
                              "robot program running?")

    def suction(self, on: bool) -> None:
        self.output(self.wiring.output, on, "suction_output")

    def generator_on(self) -> None:
        """The vacuum generator's output on, before anything moves (as ENME480's bridge does at its start)."""
        pin = self.wiring.generator
        if pin is not None:
            self.output(pin, True, GENERATOR_KEY)
            self.say(f"vacuum generator on: {output_name(pin)} (calibration io.{GENERATOR_KEY})")

    def stop_active(self) -> bool:
        """Cancel the running goal and wait for the arm to stop; False: none was running."""
        handle, self.active = self.active, None
        if handle is None or handle.done():
            return False
        self._cancel(handle)
        self.at_rest()
        return True

    def move_to(self, q1: FloatArray, speed: float, what: str) -> float:
        """A slow goal from where the arm is to ``q1``; returns its duration [s]."""
        goal = move_goal(self.q(), q1, self.plan.station, speed)
        self.run_goal(goal, what)
        return goal.points[-1].time_from_start_s

    def at_rest(self) -> None:
        """Wait until the arm stops (the controller's stop ramp after a cancel)."""
        history: list[FloatArray] = []

        def still() -> bool:
            history.append(self.q())
            return len(history) > 10 and float(np.max(np.abs(history[-1] - history[-10]))) < 1e-4

        self.sleep(self.cfg.rest_timeout_s, still)

    # ------------------------------------------------------------------------------------------ steps
    def announce(self, move: int) -> None:
        """The progress line of ``move`` (0-based), the same as the course interface's solve prints."""
        moves = self.plan.moves
        self.say(f"move {move + 1}/{len(moves)}: {describe_move(moves[move])}")

    def start(self) -> float:
        """Bring the arm to where the plan starts, or refuse (see the module docstring); returns the wall time."""
        self.check_program()
        q0, q = self.plan.trajectory.q[0], self.q()
        off = np.abs(q - q0)
        far = float(off.max())
        if far <= self.cfg.start_tolerance_rad:
            return 0.0
        joint = CONTROLLER_JOINTS[int(off.argmax())]
        where = f"the arm is {far:.3f} rad from where the plan starts ({joint})"
        if self.cfg.far_start == "refuse":
            raise DriverError(f"{where}: expected within {self.cfg.start_tolerance_rad:g} rad; bring it there first "
                              "(the station's home)")
        t0 = self.tr.now()
        goal = move_goal(q, q0, self.plan.station, self.cfg.approach_speed)
        self.say(f"{where}: moving there first at {100 * self.cfg.approach_speed:g} % speed "
                 f"({goal.points[-1].time_from_start_s:.1f} s)")
        self.run_goal(goal, "to the plan's start")
        return self.tr.now() - t0

    def dwell(self, s: Stretch) -> None:
        cfg = self.cfg
        t0 = self.tr.now()
        if s.kind == "grasp":
            self.suction(True)
            if not self.sleep(cfg.grasp_timeout_s, self.held):
                raise _HaltError("missing")
            self.sleep(s.duration_s - (self.tr.now() - t0))
        else:
            self.suction(False)
            self.sleep(cfg.release_timeout_s, lambda: not self.held())
            self.sleep(s.duration_s - (self.tr.now() - t0))

    def halt(self, kind: str, move: int) -> SuctionFaultError:
        """Suction off, the arm at rest, then home; the error to raise."""
        if kind == "missing" and no_vacuum(self.tr.latest().io, self.wiring, self.plan.station.suction):
            kind = "vacuum"
        feedback = feedback_text(self.tr.latest().io, self.wiring, outputs=kind == "vacuum")
        self.suction(False)
        self.at_rest()
        self.move_to(self.plan.station.q_home_array, self.cfg.home_speed, "home after the halt")
        moves = self.plan.moves
        mv = moves[move]
        where = (f"at tower {mv.from_tower + 1} height {mv.from_height + 1}" if kind != "dropped"
                 else f"while carrying it from tower {mv.from_tower + 1} to tower {mv.to_tower + 1}")
        block = f"{block_colour(mv.block)} block {mv.block + 1}"
        what = {"missing": f"{block} is missing {where}", "dropped": f"{block} was dropped {where}",
                "vacuum": f"no vacuum at the grasp of {block} {where}"}[kind]
        hint = vacuum_hint(self.wiring) if kind == "vacuum" else ""
        return SuctionFaultError(f"suction fault in move {move + 1}/{len(moves)}: {what} ({feedback}); halted, "
                                 f"suction off, arm returned home{hint}")


def _all_off(run: _Solve, failing: bool) -> None:
    """The way out: cancel a running goal (and let the arm stop), then every suction output off, the cup's
    first (all but those this solve has already seen switched off). While ``failing`` (an exception, an
    interrupt, on its way out) nothing here may replace it: a step that fails, even by a second Ctrl-C, is said
    and the next one still runs; otherwise a failure raises."""
    failed: list[str] = []
    done: list[str] = []
    steps: list[tuple[str, str, Callable[[], object]]] = [
        ("the running goal canceled", "the running goal", run.stop_active)]
    for pin, key in ((run.wiring.output, "suction_output"), (run.wiring.generator, GENERATOR_KEY)):
        if pin is not None and run.last.get(pin) is not False:
            steps.append((f"{output_name(pin)} off", output_name(pin),
                          functools.partial(run.output, pin, False, key)))
    for said, what, step in steps:
        try:
            if step() is not False:
                done.append(said)
        except (Exception, KeyboardInterrupt) as exc:
            if not failing:
                raise
            failed.append(f"{what} ({type(exc).__name__}{': ' if str(exc) else ''}{exc})")
    if failing and done:
        run.say(f"stopping: {', '.join(done)}")
    elif not failing and run.wiring.generator is not None:
        run.say(f"vacuum generator off: {output_name(run.wiring.generator)}")
    if failed:
        run.say(f"on the way out, could not switch off or stop: {'; '.join(failed)}: switch the outputs "
                "off on the pendant (I/O tab)")


def run_driver_solve(transport: DriverTransport, plan: Plan, wiring: SuctionWiring,
                     config: DriverSolveConfig | None = None,
                     log: Callable[[str], None] | None = None) -> DriverSolveResult:
    """Execute ``plan`` through ``transport`` (connected) with the lab's suction checks (see the module docstring).
    Every suction output (``wiring.outputs``) is off when this returns or raises, on any path.

    Raises:
        SuctionFaultError: a block was missing or dropped, or the cup had no vacuum; the arm has halted (suction
            off, home).
        DriverGoalError: the controller rejected or aborted a goal (suction off).
        ProgramStoppedError: the External Control program stopped mid-solve (suction off, the arm where it was).
        DriverError: the arm is far from the plan's start (``far_start="refuse"``), the program is not running, a
            goal timed out, the joint states stopped, or ``set_io`` failed.
    """
    cfg = config if config is not None else DriverSolveConfig()
    run = _Solve(transport, plan, wiring, cfg, log if log is not None else (lambda _s: None))
    try:
        result = _execute(run)
    except BaseException:
        _all_off(run, failing=True)
        raise
    _all_off(run, failing=False)
    return result


def _execute(run: _Solve) -> DriverSolveResult:
    """The generator on, the arm to the plan's start, the plan's stretches; the halt raised on a suction fault."""
    transport, plan = run.tr, run.plan
    stretches = plan_stretches(plan)
    run.n_goals = sum(s.kind == "motion" for s in stretches)
    t0 = transport.now()
    run.generator_on()
    approach = run.start()
    t_plan = transport.now()
    move = -1
    transport.record.start()
    try:
        for i, s in enumerate(stretches):
            transport.record.label = i
            if s.move > move:
                run.announce(s.move)
            move = s.move if s.move >= 0 else move
            if s.goal is None:
                run.dwell(s)
                continue
            what = "home" if s.move < 0 and move >= 0 else ("carry" if s.carrying else "approach") + \
                (f" of move {s.move + 1}" if s.move >= 0 else "")
            run.run_goal(s.goal, what, s.carrying)
    except _HaltError as halt:
        transport.record.stop()
        raise run.halt(halt.kind, move) from None
    finally:
        transport.record.stop()
    now = transport.now()
    t, q, stretch = transport.record.samples()
    path = path_deviation(plan, t, q, stretch_windows(plan, stretches)[stretch]) if len(q) else None
    return DriverSolveResult(plan.moves, run.goals, now - t0, approach, now - t_plan, plan.duration_s, path)
