"""The station node's scaffolding, whatever the middleware: options, inbox, control loop, report, signals.

:class:`StationCore` holds the simulated station (:class:`~ur3hanoi.sim.world.MoveJWorld` driven by a
:class:`~ur3hanoi.interface.controller.StationDriver`) and runs it in real time; a transport binding
(:class:`ur3hanoi.interface.ros1.server.RosStation` on rospy, :class:`ur3hanoi.interface.ros2.server.Ros2Station` on
Cyclone DDS) subclasses it, opens its topics and passes what arrives to :meth:`StationCore.on_command` (and
:meth:`~StationCore.on_spawn`, :meth:`~StationCore.on_remove`), and publishes the feedback in :meth:`StationCore.loop`'s
``publish`` step.

Real time: one world step per control period on the wall clock (absolute schedule; a late cycle is caught up by
the following ones, so world time never drifts from wall time); the lag of every cycle's start behind its schedule
is measured (:class:`LoopTiming`).

A flood cannot stall the loop: callbacks only append to a bounded inbox (:data:`INBOX_MAX` messages; more are
refused as "inbox full" and counted); each cycle handles at most what the inbox held when it started; refusals and
topic messages are logged through :class:`~ur3hanoi.interface.lograte.RateLimitedLog` (at most one line per topic and
second, with counts); the records are bounded (:mod:`ur3hanoi.interface.controller`, world events), so memory and the
report do not grow with the number of commands.

Rendering (``frames``/``video`` options, ``--frames``/``--video``): :meth:`StationCore.rendering` starts a
separate low-priority process (:class:`ur3hanoi.interface.render.FrameProcess`); :meth:`StationCore.loop` offers it the
joint state once per frame period of world time (dropped while it is busy, so the loop keeps real time), and the
report's ``frames`` says how many were rendered and dropped.

The JSON report (:meth:`StationCore.report`): commands executed (with duration, settle time and rest error),
refused, suction events, faults, spawns, final block positions (tower/height, or none = off-grid), loop timing,
rendered frames, plus the binding's own sections. It is written on SIGINT/SIGTERM and at the end of
``duration_s``, and on SIGUSR1 without stopping: to ``options.report`` (atomically) or, without it, to
``report_out``.
"""

from __future__ import annotations

import bisect
import gc
import json
import math
import signal
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any, ClassVar

from ur3hanoi.interface.errors import CommandError, RosError

INBOX_MAX = 200
"""Messages the callbacks may leave for the control loop; more are refused (counted, logged once a second)."""

LAG_BINS_MS: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""Upper edges [ms] of the loop-lag histogram in the report (a last bin counts the rest)."""

_SUCTION_KINDS = frozenset({"suction_on", "suction_off", "grasp", "release"})


@dataclass(frozen=True)
class CoreOptions:
    """What every station runs (0-based towers/heights/grasps; CLI numbers from 1).

    Attributes:
        calibration: station calibration file or shipped name.
        start: tower the blocks are spawned on.
        n_blocks: number of blocks (None: the grid's heights).
        removed: height left empty at spawn (fault injection), or None.
        drop_on_grasp: the block of this grasp falls off during the next motion (fault injection), or None.
        seed: seed of the analog suction feedback's noise.
        rate_hz: control and publishing rate [Hz]; its period must be a multiple of the 2 ms physics step.
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
    rate_hz: float = 125.0
    report: Path | None = None
    duration_s: float | None = None
    suction_profile: str | None = None
    frames: Path | None = None
    video: Path | None = None


class LoopTiming:
    """Lag of each control cycle's start behind its wall-clock schedule [s], and a histogram of it."""

    def __init__(self, period_s: float) -> None:
        self.period_s = period_s
        self.cycles = 0
        self.worst_lag_s = 0.0
        self.total_lag_s = 0.0
        self.late_cycles = 0  # started more than one period late
        self.histogram = [0] * (len(LAG_BINS_MS) + 1)

    def add(self, lag_s: float) -> None:
        self.cycles += 1
        self.total_lag_s += max(0.0, lag_s)
        self.worst_lag_s = max(self.worst_lag_s, lag_s)
        if lag_s > self.period_s:
            self.late_cycles += 1
        self.histogram[bisect.bisect_right(LAG_BINS_MS, 1e3 * lag_s)] += 1

    def as_dict(self, wall_s: float) -> dict[str, Any]:
        return {"rate_hz": round(1.0 / self.period_s, 3), "period_s": self.period_s, "cycles": self.cycles,
                "publish_rate_hz": round(self.cycles / wall_s, 2) if wall_s > 0 else None,
                "worst_lag_s": round(self.worst_lag_s, 6),
                "mean_lag_s": round(self.total_lag_s / self.cycles, 6) if self.cycles else None,
                "late_cycles": self.late_cycles,
                "lag_histogram_ms": {**{f"<{b:g}": n for b, n in zip(LAG_BINS_MS, self.histogram, strict=False)},
                                     f">={LAG_BINS_MS[-1]:g}": self.histogram[-1]}}


class StationCore:
    """The simulated station as a real-time node without a transport (see the module docstring).

    A binding sets :attr:`TOPIC_LOG` (the log-line prefix of each kind of message), may override
    :meth:`_command` (how a command message becomes a :meth:`StationDriver.submit
    <ur3hanoi.interface.controller.StationDriver.submit>`), :meth:`_emit` (where log lines go) and
    :meth:`_report_transport` (its report section), and calls :meth:`loop` with its receive and publish steps
    inside :meth:`signals` and :meth:`rendering` (then :meth:`close_sink` before the final report).

    Args:
        options: what to run.
        out: where the ready line and info lines go.
        report_out: where the JSON report goes without ``options.report``.
    """

    TOPIC_LOG: ClassVar[dict[str, str]] = {"command": "command rejected, the arm does not move",
                                           "spawn": "spawn", "remove": "remove_block"}
    """Prefix of the log lines about each kind of message."""

    def __init__(self, options: CoreOptions, out: Callable[[str], None],
                 report_out: Callable[[str], None]) -> None:
        from ur3hanoi.interface.controller import StationDriver
        from ur3hanoi.interface.lograte import RateLimitedLog
        from ur3hanoi.sim.config import SimConfig
        from ur3hanoi.sim.world import MoveJWorld
        from ur3hanoi.station.calibration import load_station, with_suction_profile

        self.options = opts = options
        self.out = out
        self.report_out = report_out
        self.station = load_station(opts.calibration)
        if opts.suction_profile is not None:
            self.station = with_suction_profile(self.station, opts.suction_profile)
        n_blocks = self.station.n_heights if opts.n_blocks is None else opts.n_blocks
        if not 1 <= n_blocks <= self.station.n_heights:
            raise RosError(f"{n_blocks} blocks is invalid: expected 1..{self.station.n_heights} (the grid's heights)")
        if not (math.isfinite(opts.rate_hz) and 50.0 <= opts.rate_hz <= 500.0):
            raise RosError(f"rate {opts.rate_hz} Hz is invalid: expected 50..500 Hz (the period a multiple of 2 ms)")
        if opts.drop_on_grasp is not None and opts.drop_on_grasp < 0:
            raise RosError(f"grasp {opts.drop_on_grasp + 1} is invalid: expected a grasp number >= 1")
        config = SimConfig(period_s=1.0 / opts.rate_hz, seed=opts.seed)
        self.world = MoveJWorld(self.station, opts.start, n_blocks, opts.removed, config, opts.drop_on_grasp)
        self.driver = StationDriver(self.world)
        self.timing = LoopTiming(config.period_s)
        self.reports_written = 0
        self._inbox: deque[tuple[str, Any]] = deque()
        self._overflow: dict[str, int] = {}
        self._overflow_lock = threading.Lock()
        self.log = RateLimitedLog(self._emit)
        self._stop = False
        self._dump = False
        self._wall0 = 0.0
        self._wall_end: float | None = None
        if opts.frames is not None and opts.video is not None:
            raise RosError("give at most one of frames (a PNG folder) and video (an MP4 file)")
        self._sink: Any = None  # the FrameProcess while rendering
        self._frames: dict[str, int] | None = None  # its final counts once closed
        self._next_frame_s = 0.0  # world time of the next frame [s]

    # ---------------------------------------------------------------------------------------------- callbacks
    def _offer(self, kind: str, payload: Any) -> None:
        """Called in the transport's threads: hand a message to the control loop, or count it when the inbox is
        full."""
        if len(self._inbox) < INBOX_MAX:
            self._inbox.append((kind, payload))
        else:
            with self._overflow_lock:
                self._overflow[kind] = self._overflow.get(kind, 0) + 1

    def on_command(self, msg: Any) -> None:
        """A command message (any thread; ``destination``, ``v``, ``a``, ``io_0``): it waits in the inbox for
        :meth:`cycle`."""
        self._offer("command", msg)

    def on_spawn(self, tower: Any) -> None:
        """Respawn every block on ``tower`` (numbered from 1), in the next :meth:`cycle`."""
        self._offer("spawn", tower)

    def on_remove(self, block: Any) -> None:
        """Take block ``block`` (numbered from 1, 1 = bottom) away, in the next :meth:`cycle`."""
        self._offer("remove", block)

    def _emit(self, level: str, text: str) -> None:
        """Write one log line (``level`` of :data:`ur3hanoi.interface.lograte.LEVELS`)."""
        self.out(text)

    def _command(self, msg: Any) -> None:
        """Queue one command message or raise :class:`CommandError` (recorded by the driver)."""
        self.driver.submit(msg.destination, msg.v, msg.a, msg.io_0)

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
        with self._overflow_lock:
            overflow, self._overflow = self._overflow, {}
        for kind, n in overflow.items():
            reason = f"the station's inbox is full ({INBOX_MAX} messages not yet handled): message dropped"
            for _ in range(n):
                if kind == "command":
                    self.driver.refuse(reason)
                self.log.log(self.TOPIC_LOG[kind], "error", reason)
        for _ in range(len(self._inbox)):
            kind, payload = self._inbox.popleft()
            if kind == "command":
                self.submit_command(payload)
            elif kind == "spawn":
                n = self.station.n_towers
                if isinstance(payload, int) and 1 <= payload <= n:
                    self.world.spawn(payload - 1)
                    self.log.log(self.TOPIC_LOG[kind], "info",
                                 f"{self.world.n_blocks} blocks respawned on tower {payload}")
                else:
                    self.log.log(self.TOPIC_LOG[kind], "error", f"tower {payload!r} is invalid: expected 1..{n}")
            else:
                n = self.world.n_blocks
                if isinstance(payload, int) and 1 <= payload <= n:
                    what = self.world.remove(payload - 1)
                    self.log.log(self.TOPIC_LOG[kind], "warn", f"block {payload} {what}")
                else:
                    self.log.log(self.TOPIC_LOG[kind], "error", f"block {payload!r} is invalid: expected 1..{n}")
        self.log.flush()

    # --------------------------------------------------------------------------------------------- rendering
    def open_sink(self) -> None:
        """Start the rendering process when ``frames`` or ``video`` is set (a binding calls it before its transport
        starts threads, so a slow start cannot delay messages; :meth:`rendering` does both)."""
        opts = self.options
        if self._sink is not None or (opts.frames is None and opts.video is None):
            return
        from ur3hanoi.interface.render import FrameProcess

        self._sink = FrameProcess(opts.calibration, self.world.n_blocks, opts.frames, opts.video)
        self._next_frame_s = self.world.time

    def close_sink(self) -> None:
        """Finish the PNG folder or video and stop the rendering process (the report then has its final counts);
        nothing when not rendering or already closed."""
        if self._sink is not None and self._frames is None:
            self._frames = self._sink.close()

    @contextmanager
    def rendering(self) -> Iterator[None]:
        """:meth:`open_sink` now, :meth:`close_sink` at the end (also when the block raises)."""
        self.open_sink()
        try:
            yield
        finally:
            self.close_sink()

    def offer_frame(self) -> None:
        """Send the joint state to the rendering process when a frame period of world time has passed."""
        sink = self._sink
        if sink is None or self._frames is not None or self.world.time + 1e-9 < self._next_frame_s:
            return
        sink.offer(self.world.scene.data.qpos)
        self._next_frame_s += 1.0 / sink.fps

    def _frames_report(self) -> dict[str, int] | None:
        if self._frames is not None:
            return self._frames
        return None if self._sink is None else {"rendered": self._sink.rendered, "dropped": self._sink.dropped}

    def cycle(self) -> None:
        """One control period without a transport: handle the inbox, then one driver and world step."""
        self._drain()
        self.driver.cycle()

    # ------------------------------------------------------------------------------------------------ report
    def _report_transport(self) -> dict[str, Any]:
        """The binding's sections after ``suction`` (e.g. the master, the DDS domain)."""
        return {}

    def report(self) -> dict[str, Any]:
        """The JSON report (see the module docstring); numbering from 1."""
        w, st = self.world, self.station
        events = [e.as_dict() for e in w.events]  # the last EVENTS_KEPT; counts of all in "event_counts"
        wall = (self._wall_end or time.perf_counter()) - self._wall0 if self._wall0 else 0.0
        holding = w.holding
        return {
            "station": {"name": st.name, "calibration": st.source, "sha256": st.sha256, "robot": st.robot.name},
            "suction": w.cup.profile.as_dict(),
            **self._report_transport(),
            "blocks": w.n_blocks,
            "start_tower": self.options.start + 1,
            "wall_time_s": round(wall, 3),
            "world_time_s": round(w.time, 3),
            "control": self.timing.as_dict(wall),
            "commands": self.driver.summary(),
            "executed": [m.as_dict() for m in self.driver.executed],
            "rejected": [r.as_dict() for r in self.driver.rejected],
            "suction_events": [e for e in events if e["kind"] in _SUCTION_KINDS],
            "faults": [e for e in events if e["kind"] in ("removed", "dropped")],
            "spawns": [e for e in events if e["kind"] == "spawn"],
            "event_counts": dict(w.event_counts),
            "log_lines": self.log.lines,
            "final": {
                "q": [round(float(x), 9) for x in w.q],
                "ready": self.driver.ready,
                "suction_on": w.suction_on,
                "holding": None if holding is None else holding + 1,
                "at_home": w.at_home(),
                "blocks": [b.as_dict() for b in w.blocks()],
            },
            "frames": self._frames_report(),
            "reports_written": self.reports_written + 1,
        }

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
    def _signal(self, signum: int, _frame: FrameType | None) -> None:
        if signum == signal.SIGUSR1:
            self._dump = True
        else:
            self._stop = True

    @contextmanager
    def signals(self) -> Iterator[None]:
        """SIGINT/SIGTERM stop :meth:`loop`, SIGUSR1 writes a report; the previous handlers are restored after."""
        handled = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
        previous = {s: signal.signal(s, self._signal) for s in handled}
        try:
            yield
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)

    def loop(self, ready_line: str, receive: Callable[[], None], publish: Callable[[], None],
             running: Callable[[], bool] = lambda: True) -> None:
        """Write ``ready_line``, then every control period: ``receive`` (take what arrived), :meth:`cycle`,
        ``publish`` (the feedback), :meth:`offer_frame` (when rendering); a SIGUSR1 report; until stopped,
        ``running()`` is false or ``duration_s`` passed. Pending log summaries are written at the end."""
        period = self.world.config.period_s
        self.out(ready_line)
        # Everything built so far lives as long as the node: keep the cyclic collector from scanning it in the loop.
        gc.collect()
        gc.freeze()
        self._wall0 = next_t = time.perf_counter()
        try:
            while not self._stop and running():
                now = time.perf_counter()
                self.timing.add(now - next_t)
                receive()
                self.cycle()
                publish()
                self.offer_frame()
                if self._dump:
                    self._dump = False
                    self.write_report()
                if self.options.duration_s is not None and now - self._wall0 >= self.options.duration_s:
                    break
                next_t += period
                delay = next_t - time.perf_counter()
                if delay > 0:
                    time.sleep(delay)
        finally:
            self._wall_end = time.perf_counter()
            self.log.flush(force=True)
