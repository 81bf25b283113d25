"""A station that serves the official UR driver's interface (``ros-station --driver ur``), without its transport.

:class:`DriverStation` is a :class:`~ur3hanoi.interface.common.station.ServerCore` (real-time loop, inbox, rate-limited
log, report, rendering) whose arm is the simulated UR robot under the driver's scaled joint trajectory controller:

- the robot: :class:`ur3hanoi.sim.servo_world.ServoWorld` (joint limits, its own speed scaling times the slider
  ``speed_scaling``, the servo, suction, blocks);
- the controller: :class:`~ur3hanoi.interface.urdriver.follower.TrajectoryFollower` with the options' profile;
- the IO: :class:`~ur3hanoi.interface.urdriver.io.IoBoard`: the cup pulls while the digital output the calibration's
  wiring names is on and, on a cell with one, the vacuum generator's output too
  (:class:`ur3hanoi.station.suction_wiring.SuctionWiring`; without the generator the cup is open to the air: no
  vacuum, nothing picked, the sensor at its no-vacuum level), and its feedback (today's suction model:
  vacuum switch = ``DIGIN`` bit 0, vacuum sensor = ``AIN0``) reads on the wiring's digital and analog inputs.

A binding calls, from any thread, :meth:`~DriverStation.on_goal`, :meth:`~DriverStation.on_cancel`,
:meth:`~DriverStation.set_io`, :meth:`~DriverStation.on_hold` (and :meth:`~DriverStation.on_spawn`,
:meth:`~DriverStation.on_remove`); goals and cancels wait in the inbox for the next control cycle. Every cycle it
publishes :attr:`DriverStation.output` (:class:`CycleOutput`): the joint states, ``io_states``, the speed scaling, the
goals decided, the active goal's feedback and the results.
"""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.common.station import ServerCore, ServerOptions
from ur3hanoi.interface.urdriver.controllers import ControllerManager, Ros1ControllerManager
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS
from ur3hanoi.interface.urdriver.follower import Feedback, Outcome, TrajectoryFollower
from ur3hanoi.interface.urdriver.goal import Rejection, TrajectoryGoal
from ur3hanoi.interface.urdriver.io import IoBoard, IoStates, SetIo
from ur3hanoi.interface.urdriver.profile import ROS1_SCALED, ControllerProfile
from ur3hanoi.interface.urdriver.records import DriverRecords

if TYPE_CHECKING:
    from ur3hanoi.sim.config import SimConfig
    from ur3hanoi.sim.servo_world import ServoWorld


@dataclass(frozen=True)
class DriverStationOptions(ServerOptions):
    """:class:`~ur3hanoi.interface.common.station.ServerOptions` and

    Attributes:
        speed_scaling: the pendant's speed slider, in (0, 1].
        profile: the controller's defaults and rules (ROS 1 or ROS 2).
        program_stop_at_s, program_resume_at_s: fault injection: the External Control program stops (as when the
            pendant's stop button is pressed) and starts again at these world times [s] (None: never).
        initial_controller: ROS 2: the controller manager's initial motion controller
            (:class:`~ur3hanoi.interface.urdriver.controllers.ControllerManager`); None: ROS 1's controller manager
            (:class:`~ur3hanoi.interface.urdriver.controllers.Ros1ControllerManager`).
    """

    rate_hz: float | None = None
    speed_scaling: float = 1.0
    profile: ControllerProfile = ROS1_SCALED
    program_stop_at_s: float | None = None
    program_resume_at_s: float | None = None
    initial_controller: str | None = None


@dataclass(frozen=True)
class CycleOutput:
    """What the driver publishes after one control cycle.

    Attributes:
        t_s: world time [s].
        names, q, qd, effort: the measured joint states [rad, rad/s, N m] in the controller's joint order.
        io: ``io_states``.
        speed_scaling: the speed scaling as a fraction (publish it times the profile's ``speed_scaling_unit``).
        decisions: goals decided this cycle: (key, None = accepted, or the rejection).
        feedback: the active goal's (key, feedback), or None.
        results: goals that ended this cycle: (key, outcome).
        program_running: whether the External Control program runs (the driver's ``robot_program_running``).
    """

    t_s: float
    names: tuple[str, ...]
    q: FloatArray
    qd: FloatArray
    effort: FloatArray
    io: IoStates
    speed_scaling: float
    decisions: tuple[tuple[Hashable, Rejection | None], ...] = ()
    feedback: tuple[Hashable, Feedback] | None = None
    results: tuple[tuple[Hashable, Outcome], ...] = ()
    program_running: bool = True


class StationCall(Protocol):
    """A call answered in the control thread (:class:`ur3hanoi.interface.urdriver.services.ServiceCall`)."""

    def answer(self, station: DriverStation) -> None: ...


class DriverStation(ServerCore["ServoWorld"]):
    """The simulated UR robot behind the official driver's interface (see the module docstring)."""

    options: DriverStationOptions

    TOPIC_LOG: ClassVar[dict[str, str]] = {"goal": "follow_joint_trajectory", "cancel": "follow_joint_trajectory",
                                           "hold": "hold_arm", "io": "set_io", "spawn": "spawn",
                                           "remove": "remove_block", "program": "program_running"}

    def __init__(self, options: DriverStationOptions, out: Any, report_out: Any) -> None:
        super().__init__(options, out, report_out)
        self.io = IoBoard()
        self.records = DriverRecords()
        w = self.world
        self.follower = TrajectoryFollower(options.profile, w.q, self.station.limits.a_max)
        self._decisions: list[tuple[Hashable, Rejection | None]] = []
        self._switch = False
        self._effort_ids = w.servo.act_ids
        self._program_done: set[float] = set()
        self.program_running = True
        self.controllers: ControllerManager | Ros1ControllerManager = \
            Ros1ControllerManager() if options.initial_controller is None else \
            ControllerManager(options.initial_controller)
        self._owner = self.controllers.trajectory_controller()
        if options.program_stop_at_s is not None and options.program_stop_at_s <= 0.0:
            self._scheduled_program()  # stopped from the start: the first output says so
        self.output = self._output((), None, ())

    def _build_world(self, config: SimConfig, n_blocks: int) -> ServoWorld:
        from ur3hanoi.sim.servo_world import ServoWorld

        opts = self.options
        return ServoWorld(self.station, opts.start, n_blocks, opts.removed, config, opts.drop_on_grasp,
                          opts.speed_scaling)

    # ---------------------------------------------------------------------------------------------- callbacks
    def on_goal(self, key: Hashable, goal: TrajectoryGoal) -> None:
        """A ``FollowJointTrajectory`` goal (any thread): decided in the next cycle (:attr:`CycleOutput.decisions`)."""
        self.inbox.offer("goal", (key, goal))

    def on_cancel(self, key: Hashable) -> None:
        """A cancel request for goal ``key`` (any thread)."""
        self.inbox.offer("cancel", (key, time.monotonic()))

    def on_program(self, running: bool) -> None:
        """Fault injection (any thread): the robot program stopped (False) or started again (True) on the pendant;
        the driver stops its trajectory controller meanwhile."""
        self.inbox.offer("program", bool(running))

    def on_hold(self, seconds: float) -> None:
        """Fault injection (any thread): clamp the arm where it is for ``seconds`` (0 releases it)."""
        self.inbox.offer("hold", seconds)

    def set_io(self, fun: int, pin: int, state: float) -> SetIo | None:
        """``set_io`` (any thread): the write, queued for the next cycle, or None (``success = false``)."""
        write = self.io.request(fun, pin, state)
        self.inbox.offer("io", (fun, pin, state, write is not None))
        return write

    def _dropped(self, kind: str, reason: str) -> None:
        pass  # a goal lost to a full inbox stays pending: the client's own timeout notices

    def _handle(self, kind: str, payload: Any) -> None:
        t = self.world.time
        if kind == "goal":
            key, goal = payload
            decision = self.follower.submit(key, goal)
            self._decisions.append((key, decision))
            self.records.received(key, goal, t, decision)
            if decision is not None:
                self.log.log(self.TOPIC_LOG[kind], "error", f"goal {key} rejected: {decision.describe()}")
        elif kind == "cancel":
            key, arrived = payload
            if self.follower.cancel(key):
                self.records.canceled(t, self.follower.cycle + 1, arrived)  # handled before this cycle's update
        elif kind == "hold":
            self.world.hold_arm(float(payload))
            self.log.log(self.TOPIC_LOG[kind], "warn", f"the arm is held for {float(payload):g} s")
        elif kind == "io":
            self.records.io_call(t, *payload)
        elif kind == "program":
            self.set_program(bool(payload))
        elif kind == "service":
            payload.answer(self)
        else:
            super()._handle(kind, payload)

    def on_service(self, request: StationCall) -> None:
        """A ``controller_manager`` or dashboard call (any thread): answered in the next control cycle."""
        self.inbox.offer("service", request)

    def sync_controllers(self) -> None:
        """The follower runs while the program does and (ROS 2) a trajectory controller is active; a switch to
        another one ends the running goal as a deactivation does."""
        owner = self.controllers.trajectory_controller()
        running = self.program_running and owner is not None
        if owner != self._owner and self.follower.running:
            self.follower.set_running(False)
        self._owner = owner
        self.follower.set_running(running)

    def set_program(self, running: bool) -> None:
        """The External Control program stops or starts (control thread): the controllers with it (the driver's
        ``controller_stopper``); ``io_states`` and the joint states go on."""
        if running == self.program_running:
            return
        self.program_running = running
        self.controllers.program(running)
        self.sync_controllers()
        self.records.program_changed(self.world.time, running)
        self.log.log(self.TOPIC_LOG["program"], "warn", "the External Control program runs again" if running else
                     "the External Control program stopped: the trajectory controller is stopped, goals are refused")

    def _scheduled_program(self) -> None:
        """``--program-stop-at`` / ``--program-resume-at``: each once, when the world time reaches it."""
        opts, t = self.options, self.world.time
        for at, running in ((opts.program_stop_at_s, False), (opts.program_resume_at_s, True)):
            if at is not None and at not in self._program_done and t >= at - 1e-9:
                self._program_done.add(at)
                self.set_program(running)

    # ------------------------------------------------------------------------------------------------ cycle
    def _step(self) -> None:
        """One control cycle: the IO writes, the controller, the robot, the feedback on the inputs."""
        self._scheduled_program()
        w, period = self.world, self.world.config.period_s
        self.io.cycle()
        wiring = self.station.wiring
        vacuum = wiring.generator is None or self.io.digital_out(wiring.generator)  # the cell's generator, if any
        w.set_suction(self.io.digital_out(wiring.output) and vacuum)
        s = w.speed_scaling
        d = self.follower.update(w.q, w.qd, period, s)
        assert d.qd is not None and d.qdd is not None
        w.step(d.q, d.qd * s, d.qdd * s * s)
        fb = w.feedback()
        held = bool(fb.digin & 1)
        self.io.set_inputs({wiring.switch_input: held}, {wiring.sensor_input: fb.ain0})
        active = self.follower.active
        self.records.switch(self._switch, held, active is not None and w.suction_on, self.follower.cycle,
                            time.monotonic())
        self._switch = held
        self.records.running(None if active is None else active.key, self.follower.max_path_error, s)
        outcomes = self.follower.take_outcomes()
        for o in outcomes:
            self.records.ended(o, w.time)
            if o.status == "aborted":
                self.log.log(self.TOPIC_LOG["goal"], "warn", f"goal {o.key} aborted: {o.code.name} {o.error_string}")
        fbk = self.follower.feedback()
        self.output = self._output(tuple(self._decisions), None if fbk is None or active is None else
                                   (active.key, fbk), tuple((o.key, o) for o in outcomes))
        self._decisions = []

    def _output(self, decisions: tuple[tuple[Hashable, Rejection | None], ...],
                feedback: tuple[Hashable, Feedback] | None,
                results: tuple[tuple[Hashable, Outcome], ...]) -> CycleOutput:
        w = self.world
        effort = w.scene.data.actuator_force[self._effort_ids]  # a copy (fancy indexing)
        return CycleOutput(w.time, CONTROLLER_JOINTS, w.q, w.qd, effort, self.io.states, w.speed_scaling, decisions,
                           feedback, results, self.program_running)

    # ------------------------------------------------------------------------------------------------ report
    def _report_motion(self) -> dict[str, Any]:
        opts = self.options
        return {"driver": {"profile": opts.profile.name, "speed_slider": opts.speed_scaling,
                           "wiring": self.station.wiring.as_dict()},
                "goals": self.records.summary(),
                "goal_records": [g.as_dict() for g in self.records.goals],
                "io_calls": list(self.records.io_calls),
                "halts": [h.as_dict() for h in self.records.halts],
                "program": list(self.records.program)}

    def _report_final(self) -> dict[str, Any]:
        return {"goal_active": self.follower.active is not None, "program_running": self.program_running,
                "controllers": self._controller_states(),
                "digital_outputs_on": [pin for pin, on in enumerate(self.io.states.digital_out) if on],
                "speed_scaling": round(self.world.speed_scaling, 6)}

    def _controller_states(self) -> dict[str, str]:
        cm = self.controllers
        if isinstance(cm, Ros1ControllerManager):
            return dict(cm.states)
        return {c.name: state for c, state in cm.listing()}
