"""A station (``ros-station``, ``ros2-station``, either protocol) without its protocol and transport: options, inbox,
control cycle, report.

:class:`ServerCore` holds the simulated arm and blocks of a station and runs it in real time; a protocol's core
subclasses it with the world and what drives it (the course's ``movej`` controller:
:class:`ur3hanoi.interface.course.station.CourseStation`; the UR driver's trajectory controller:
:class:`ur3hanoi.interface.urdriver.station.DriverStation`), and a transport binding
(:class:`ur3hanoi.interface.ros1.server.RosServer` on rospy, :class:`ur3hanoi.interface.ros2.server.Ros2Server` on
Cyclone DDS, and their ``ur_*`` counterparts) subclasses that, opens its topics and passes what arrives to
:meth:`ServerCore.on_command` (and :meth:`~ServerCore.on_spawn`, :meth:`~ServerCore.on_remove`), and publishes the
feedback in :meth:`ServerCore.loop`'s ``publish`` step.

Real time: one world step per control period on the wall clock
(:class:`~ur3hanoi.interface.common.realtime.RealTimeLoop`: an absolute schedule, the lag of every cycle measured).

A flood cannot stall the loop: callbacks only append to a bounded inbox
(:class:`~ur3hanoi.interface.common.inbox.Inbox`, :data:`~ur3hanoi.interface.common.inbox.INBOX_MAX` messages; more
are refused as "inbox full" and counted); each cycle handles at most what the inbox held when it started; refusals
and topic messages are logged through :class:`~ur3hanoi.interface.common.lograte.RateLimitedLog` (at most one line
per topic and second, with counts); the records are bounded (the protocol's controller, world events), so memory and
the report do not grow with the number of commands.

Rendering (``frames``/``video`` options, ``--frames``/``--video``): :meth:`ServerCore.rendering` starts a
separate low-priority process (:class:`ur3hanoi.interface.common.render.FrameOutput`); :meth:`ServerCore.loop` offers
it the joint state once per frame period of world time (dropped while it is busy, so the loop keeps real time), and
the report's ``frames`` says how many were rendered and dropped.

The JSON report (:meth:`ServerCore.report`): the protocol's motion sections (the course's: commands executed with
duration, settle time and rest error, and refused), suction events, faults, spawns, final block positions
(tower/height, or none = off-grid), loop timing, rendered frames, plus the binding's own sections. It is written on
SIGINT/SIGTERM and at the end of ``duration_s``, and on SIGUSR1 without stopping: to ``options.report`` (atomically)
or, without it, to ``report_out``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterator
from contextlib import AbstractContextManager, contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, ClassVar, Generic, TypeVar

from ur3hanoi.errors import InputError
from ur3hanoi.interface.common.errors import CommandError
from ur3hanoi.interface.common.inbox import INBOX_MAX, Inbox
from ur3hanoi.interface.common.realtime import RealTimeLoop
from ur3hanoi.interface.common.render import FrameOutput

if TYPE_CHECKING:
    from ur3hanoi.sim.config import SimConfig
    from ur3hanoi.sim.task_world import TaskWorld

WorldT = TypeVar("WorldT", bound="TaskWorld")

BEHIND_WARNING_S = 0.25
"""A control loop more than this [s] behind its schedule says so on its log, once a second."""
_SUCTION_KINDS = frozenset({"suction_on", "suction_off", "grasp", "release"})


@dataclass(frozen=True)
class ServerOptions:
    """What every station runs (0-based towers/heights/grasps; CLI numbers from 1).

    Attributes:
        calibration: station calibration file or shipped name.
        start: tower the blocks are spawned on.
        n_blocks: number of blocks (None: the grid's heights).
        removed: height left empty at spawn (fault injection), or None.
        drop_on_grasp: the block of this grasp falls off during the next motion (fault injection), or None.
        seed: seed of the analog suction feedback's noise.
        rate_hz: control and publishing rate [Hz]; its period must be a multiple of the 2 ms physics step. None:
            the calibration's robot's control rate (CB3 125 Hz, e-Series 500 Hz).
        report: JSON report file, or None for ``report_out``.
        duration_s: stop by itself after this wall time [s], or None (until SIGINT/SIGTERM).
        suction_profile: a named suction feedback profile (``lab_sim``, ``real``) replacing the calibration's,
            or None (the calibration's ``suction`` section).
        frames, video: offscreen rendering into a PNG folder or an MP4 file (at most one), as in ``ur3hanoi
            solve``; None: no rendering.
    """

    calibration: str = "lab_sim"
    start: int = 0
    n_blocks: int | None = None
    removed: int | None = None
    drop_on_grasp: int | None = None
    seed: int = 0
    rate_hz: float | None = 125.0
    report: Path | None = None
    duration_s: float | None = None
    suction_profile: str | None = None
    frames: Path | None = None
    video: Path | None = None


def _checked(opts: ServerOptions, n_heights: int, robot_rate_hz: float) -> tuple[int, float]:
    """The number of blocks and the rate [Hz] ``opts`` asks for, after checking them and the grasp to drop."""
    n_blocks = n_heights if opts.n_blocks is None else opts.n_blocks
    if not 1 <= n_blocks <= n_heights:
        raise InputError(f"{n_blocks} blocks is invalid: expected 1..{n_heights} (the grid's heights)")
    rate = robot_rate_hz if opts.rate_hz is None else opts.rate_hz
    if not (math.isfinite(rate) and 50.0 <= rate <= 500.0):
        raise InputError(f"rate {rate} Hz is invalid: expected 50..500 Hz (the period a multiple of 2 ms)")
    if opts.drop_on_grasp is not None and opts.drop_on_grasp < 0:
        raise InputError(f"grasp {opts.drop_on_grasp + 1} is invalid: expected a grasp number >= 1")
    return n_blocks, rate


def _spawn_or_remove(core: ServerCore[Any], kind: str, payload: Any) -> None:
    """Respawn the blocks on tower ``payload`` (``spawn``) or take block ``payload`` away (``remove``), numbered
    from 1; a bad number is logged."""
    topic, w = core.TOPIC_LOG[kind], core.world
    n = core.station.n_towers if kind == "spawn" else w.n_blocks
    if not (isinstance(payload, int) and 1 <= payload <= n):
        core.log.log(topic, "error", f"{'tower' if kind == 'spawn' else 'block'} {payload!r} is invalid: expected "
                                     f"1..{n}")
    elif kind == "spawn":
        w.spawn(payload - 1)
        core.log.log(topic, "info", f"{w.n_blocks} blocks respawned on tower {payload}")
    else:
        core.log.log(topic, "warn", f"block {payload} {w.remove(payload - 1)}")


class ServerCore(Generic[WorldT]):
    """The simulated station as a real-time node without a protocol or transport (see the module docstring).

    A protocol's core provides :meth:`_build_world`, :meth:`_command`, :meth:`_dropped`, :meth:`_step`,
    :meth:`_report_motion` and :meth:`_report_final` (and may add kinds of message in :meth:`_handle`). A binding
    sets :attr:`TOPIC_LOG` (the log-line prefix of each kind of message), may override :meth:`_command`,
    :meth:`_emit` (where log lines go) and :meth:`_report_transport` (its report section), and calls :meth:`loop`
    with its receive and publish steps inside :meth:`signals` and :meth:`rendering` (then :meth:`close_sink` before
    the final report).

    Args:
        options: what to run.
        out: where the ready line and info lines go.
        report_out: where the JSON report goes without ``options.report``.
    """

    TOPIC_LOG: ClassVar[dict[str, str]] = {"command": "command rejected, the arm does not move",
                                           "spawn": "spawn", "remove": "remove_block"}
    """Prefix of the log lines about each kind of message."""

    def __init__(self, options: ServerOptions, out: Callable[[str], None],
                 report_out: Callable[[str], None]) -> None:
        from ur3hanoi.interface.common.lograte import RateLimitedLog
        from ur3hanoi.sim.config import SimConfig
        from ur3hanoi.station.calibration import load_station, with_suction_profile

        self.options = opts = options
        self.out = out
        self.report_out = report_out
        self.station = load_station(opts.calibration)
        if opts.suction_profile is not None:
            self.station = with_suction_profile(self.station, opts.suction_profile)
        n_blocks, rate = _checked(opts, self.station.n_heights, self.station.robot.control_rate_hz)
        config = SimConfig(period_s=1.0 / rate, seed=opts.seed)
        self.world: WorldT = self._build_world(config, n_blocks)
        self.clock = RealTimeLoop(config.period_s)
        self.reports_written = 0
        self.inbox = Inbox()
        self.log = RateLimitedLog(self._emit)
        self.frames = FrameOutput(opts.calibration, n_blocks, opts.frames, opts.video)

    def _build_world(self, config: SimConfig, n_blocks: int) -> WorldT:
        """The simulated station and what drives it (the protocol's core: its world and controller)."""
        raise NotImplementedError

    # ---------------------------------------------------------------------------------------------- callbacks
    def on_command(self, msg: Any) -> None:
        """A command message (any thread; ``destination``, ``v``, ``a``, ``io_0``): it waits in the inbox for
        :meth:`cycle`."""
        self.inbox.offer("command", msg)

    def on_spawn(self, tower: Any) -> None:
        """Respawn every block on ``tower`` (numbered from 1), in the next :meth:`cycle`."""
        self.inbox.offer("spawn", tower)

    def on_remove(self, block: Any) -> None:
        """Take block ``block`` (numbered from 1, 1 = bottom) away, in the next :meth:`cycle`."""
        self.inbox.offer("remove", block)

    def _emit(self, level: str, text: str) -> None:
        """Write one log line (``level`` of :data:`ur3hanoi.interface.common.lograte.LEVELS`)."""
        self.out(text)

    def _command(self, msg: Any) -> None:
        """Queue one command message or raise :class:`CommandError` (recorded by the protocol's controller)."""
        raise NotImplementedError

    def submit_command(self, msg: Any) -> bool:
        """Check and queue one command now (True), or log why it is refused (False)."""
        try:
            self._command(msg)
        except CommandError as exc:
            self.log.log(self.TOPIC_LOG["command"], "error", str(exc))
            return False
        return True

    def _drain(self) -> None:
        """Handle what the callbacks received, in order, in the control thread (the world is single-threaded):
        at most what the inbox held when the cycle started, so a flood cannot hold the loop."""
        overflow, received = self.inbox.take()
        for kind, n in overflow.items():
            reason = f"the station's inbox is full ({INBOX_MAX} messages not yet handled): message dropped"
            for _ in range(n):
                self._dropped(kind, reason)
                self.log.log(self.TOPIC_LOG[kind], "error", reason)
        for kind, payload in received:
            self._handle(kind, payload)
        self.log.flush()

    def _dropped(self, kind: str, reason: str) -> None:
        """A message of ``kind`` the full inbox refused (recorded by the protocol's controller)."""
        raise NotImplementedError

    def _handle(self, kind: str, payload: Any) -> None:
        """One message from the inbox: a command, a spawn or a removal (a subclass adds its own kinds)."""
        if kind == "command":
            self.submit_command(payload)
        else:
            _spawn_or_remove(self, kind, payload)

    # --------------------------------------------------------------------------------------------- rendering
    @contextmanager
    def rendering(self) -> Iterator[None]:
        """The rendering process started now (before the binding's transport threads), closed at the end (also
        when the block raises); a binding closes it itself (:meth:`close_sink`) before its final report."""
        self.frames.open(self.world.time)
        try:
            yield
        finally:
            self.frames.close()

    def close_sink(self) -> None:
        """Finish the PNG folder or video: the report then has the final frame counts."""
        self.frames.close()

    def cycle(self) -> None:
        """One control period without a transport: handle the inbox, then one driver and world step."""
        self._drain()
        self._step()

    def _step(self) -> None:
        """One driver and world step (the protocol's controller)."""
        raise NotImplementedError

    # ------------------------------------------------------------------------------------------------ report
    def _report_transport(self) -> dict[str, Any]:
        """The binding's sections after ``suction`` (e.g. the master, the DDS domain)."""
        return {}

    def _report_motion(self) -> dict[str, Any]:
        """The report's sections on what was commanded (the protocol's controller's records)."""
        raise NotImplementedError

    def _report_final(self) -> dict[str, Any]:
        """The protocol's controller's part of the report's ``final`` section."""
        raise NotImplementedError

    def report(self) -> dict[str, Any]:
        """The JSON report (see the module docstring); numbering from 1."""
        return _report(self)

    def write_report(self) -> dict[str, Any]:
        """Write :meth:`report` to ``options.report`` (atomically) or to ``report_out``; returns it."""
        from ur3hanoi.io.atomic import atomic_write

        report = self.report()
        text = json.dumps(report, indent=1) + "\n"
        self.reports_written += 1
        if self.options.report is not None:
            atomic_write(self.options.report, text)
        else:
            self.report_out(text.rstrip("\n"))
        return report

    # --------------------------------------------------------------------------------------------------- run
    def signals(self) -> AbstractContextManager[None]:
        """SIGINT/SIGTERM stop :meth:`loop`, SIGUSR1 writes a report; the previous handlers are restored after."""
        return self.clock.signals()

    def loop(self, ready_line: str, receive: Callable[[], None], publish: Callable[[], None],
             running: Callable[[], bool] = lambda: True) -> None:
        """Write ``ready_line``, then every control period: ``receive`` (take what arrived), :meth:`cycle`,
        ``publish`` (the feedback), a frame to the rendering process (when rendering); a SIGUSR1 report; until
        stopped, ``running()`` is false or ``duration_s`` passed."""
        def step() -> None:
            receive()
            self.cycle()
            publish()
            self.frames.offer(self.world.time, self.world.scene.data.qpos)
            lag = self.clock.timing.last_lag_s
            if lag > BEHIND_WARNING_S:  # at most one line a second (RateLimitedLog)
                self.log.log("loop", "warn", f"the station is {1e3 * lag:.0f} ms behind real time: the machine "
                             "is too busy for this control rate (close other programs, or lower --rate)")

        self.out(ready_line)
        self.clock.run(step, running, self.write_report, self.options.duration_s)


def _report(core: ServerCore[Any]) -> dict[str, Any]:
    """:meth:`ServerCore.report`."""
    w, st = core.world, core.station
    events = [e.as_dict() for e in w.events]  # the last EVENTS_KEPT; counts of all in "event_counts"
    wall = core.clock.wall_s
    holding = w.holding
    return {
        "station": {"name": st.name, "calibration": st.source, "sha256": st.sha256, "robot": st.robot.name},
        "suction": w.cup.profile.as_dict(),
        **core._report_transport(),
        "blocks": w.n_blocks,
        "start_tower": core.options.start + 1,
        "wall_time_s": round(wall, 3),
        "world_time_s": round(w.time, 3),
        "control": core.clock.timing.as_dict(wall),
        **core._report_motion(),
        "suction_events": [e for e in events if e["kind"] in _SUCTION_KINDS],
        "faults": [e for e in events if e["kind"] in ("removed", "dropped")],
        "spawns": [e for e in events if e["kind"] == "spawn"],
        "event_counts": dict(w.event_counts),
        "log_lines": core.log.lines,
        "final": {
            "q": [round(float(x), 9) for x in w.q],
            **core._report_final(),
            "suction_on": w.suction_on,
            "holding": None if holding is None else holding + 1,
            "at_home": w.at_home(),
            "blocks": [b.as_dict() for b in w.blocks()],
        },
        "frames": core.frames.counts(),
        "reports_written": core.reports_written + 1,
    }
