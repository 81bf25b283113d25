"""``ur3hanoi ros-station``: a drop-in for the course's Gazebo world and ``ur3_driver``, backed by MuJoCo.

The node speaks the course's topics and messages exactly (:mod:`ur3hanoi.ros.msgs`):

- subscribes ``/ur3/command``: each accepted command runs as the controller's ``movej``
  (:mod:`ur3hanoi.ros.movej`, ``v``/``a`` capped at the UR3's limits) after the ones before it
  (:mod:`ur3hanoi.ros.driver`), switching the suction to ``io_0`` when it starts; malformed commands are refused
  with a logged error and no motion (:mod:`ur3hanoi.ros.command`);
- publishes ``/ur3/position`` (measured joint angles, ``isReady`` false while moving or not yet within
  0.0005 rad of the destination) and ``/ur3/gripper_input`` (``DIGIN`` bit 0, ``AIN0`` from the suction model)
  every control period (8 ms: 125 Hz, like the course driver);
- subscribes ``/ur3hanoi/spawn`` (``std_msgs/Int32``, tower 1..3: respawn every block there, like
  ``lab2_spawn.py``) and ``/ur3hanoi/remove_block`` (``std_msgs/Int32``, block 1..3, 1 = bottom/green: take it
  away; a held block is dropped).

Real time: one world step per control period on the wall clock (absolute schedule; a late cycle is caught up by
the following ones, so world time never drifts from wall time). The worst lag of a cycle's start behind its
schedule is reported. A roscore is started when none answers at ``ROS_MASTER_URI`` (:mod:`ur3hanoi.ros.master`)
and stopped on exit, or when the station dies (:mod:`ur3hanoi.ros.guard`).

A flood cannot stall the loop: the ROS callbacks only append to a bounded inbox (:data:`INBOX_MAX` messages;
more are refused as "inbox full" and counted); each cycle handles at most what the inbox held when it started;
refusals and topic messages are logged through :class:`~ur3hanoi.ros.lograte.RateLimitedLog` (at most one line per
topic and second, with counts); the records are bounded (:mod:`ur3hanoi.ros.driver`, world events), so memory and
the report do not grow with the number of commands.

Listening: the station and the roscore it starts bind and advertise ``host`` (``ROS_IP``), by default
``127.0.0.1``: nothing on the lab network can reach them. ``--host ADDR`` (this machine's address on the lab
network) opens them; a master on another machine needs it. ``ROS_IP``/``ROS_HOSTNAME`` of the environment are
not used.

Output: the ready line and every info line go to ``info`` (the CLI: stderr); standard output carries only the
JSON report when there is no ``--report`` file.

``--frames``/``--video`` render in a separate low-priority process (:mod:`ur3hanoi.ros.render`), which drops
frames rather than stall the loop.

The JSON report (:meth:`RosStation.report`): commands executed (with duration, settle time and rest error),
refused, suction events, faults, final block positions (tower/height, or none = off-grid), loop timing. It is
written on SIGINT/SIGTERM and at the end of ``--duration``, and on SIGUSR1 without stopping: to ``--report FILE``
(atomically) or, without it, to stdout.
"""

from __future__ import annotations

import bisect
import gc
import ipaddress
import json
import math
import os
import signal
import sys
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

from ur3hanoi.ros.errors import CommandError, RosError

READY_LINE = "ur3hanoi ros-station: ready"
"""Written (and flushed) on stderr once the node is up: scripts wait for it."""

INBOX_MAX = 200
"""Messages the callbacks may leave for the control loop; more are refused (counted, logged once a second)."""


@dataclass(frozen=True)
class StationOptions:
    """What ``ur3hanoi ros-station`` runs (0-based towers/heights/grasps; CLI numbers from 1).

    Attributes:
        calibration: station calibration file or shipped name.
        start: tower the blocks are spawned on.
        n_blocks: number of blocks (None: the grid's heights).
        removed: height left empty at spawn (fault injection), or None.
        drop_on_grasp: the block of this grasp falls off during the next motion (fault injection), or None.
        seed: seed of the ``AIN0`` noise.
        rate_hz: control and publishing rate [Hz]; its period must be a multiple of the 2 ms physics step.
        report: JSON report file, or None for stdout.
        frames, video: offscreen rendering (PNG folder or MP4), as in ``ur3hanoi solve``.
        duration_s: stop by itself after this wall time [s], or None (until SIGINT/SIGTERM).
        master_uri: ROS master (None: ``ROS_MASTER_URI``, else http://localhost:11311).
        host: address the station and the roscore it starts listen on and advertise (``ROS_IP``); the default
            127.0.0.1 keeps them on this machine.
        suction_profile: a named suction feedback profile (``lab_sim``, ``real``) replacing the calibration's,
            or None (the calibration's ``suction`` section).
    """

    calibration: str = "lab_sim"
    start: int = 0
    n_blocks: int | None = None
    removed: int | None = None
    drop_on_grasp: int | None = None
    seed: int = 0
    rate_hz: float = 125.0
    report: Path | None = None
    frames: Path | None = None
    video: Path | None = None
    duration_s: float | None = None
    master_uri: str | None = None
    host: str = "127.0.0.1"
    suction_profile: str | None = None


LAG_BINS_MS: tuple[float, ...] = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)
"""Upper edges [ms] of the loop-lag histogram in the report (a last bin counts the rest)."""


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


_TOPIC_LOG = {"command": "ur3/command rejected, the arm does not move", "spawn": "ur3hanoi/spawn",
              "remove": "ur3hanoi/remove_block"}
"""Prefix of the log lines about each topic's messages."""


class RosStation:
    """The ``ros-station`` node (see the module docstring). :meth:`run` blocks until stopped.

    Args:
        options: what to run.
        out: where the ready line and info lines go (default: print to stderr, flushed).
        report_out: where the JSON report goes without ``options.report`` (default: print to stdout, flushed).
    """

    def __init__(self, options: StationOptions, out: Callable[[str], None] | None = None,
                 report_out: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.ros.driver import StationDriver
        from ur3hanoi.ros.lograte import RateLimitedLog
        from ur3hanoi.ros.master import MasterUri, is_loopback, master_uri_from_env
        from ur3hanoi.ros.world import StationWorld, WorldConfig
        from ur3hanoi.station import load_station

        self.options = opts = options
        self.out = out if out is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        self.report_out = report_out if report_out is not None else (lambda s: print(s, flush=True))
        self.station = load_station(opts.calibration)
        if opts.suction_profile is not None:
            from ur3hanoi.station import with_suction_profile

            self.station = with_suction_profile(self.station, opts.suction_profile)
        n_blocks = self.station.n_heights if opts.n_blocks is None else opts.n_blocks
        if not 1 <= n_blocks <= self.station.n_heights:
            raise RosError(f"{n_blocks} blocks is invalid: expected 1..{self.station.n_heights} (the grid's heights)")
        if not (math.isfinite(opts.rate_hz) and 50.0 <= opts.rate_hz <= 500.0):
            raise RosError(f"rate {opts.rate_hz} Hz is invalid: expected 50..500 Hz (the period a multiple of 2 ms)")
        if opts.drop_on_grasp is not None and opts.drop_on_grasp < 0:
            raise RosError(f"grasp {opts.drop_on_grasp + 1} is invalid: expected a grasp number >= 1")
        config = WorldConfig(period_s=1.0 / opts.rate_hz, seed=opts.seed)
        self.world = StationWorld(self.station, opts.start, n_blocks, opts.removed, config, opts.drop_on_grasp)
        self.driver = StationDriver(self.world)
        self.master_uri = opts.master_uri or master_uri_from_env()
        master = MasterUri.parse(self.master_uri)
        try:
            ipaddress.ip_address(opts.host)
        except ValueError:
            raise RosError(f"host {opts.host!r} is invalid: expected this machine's IP address (ROS_IP), e.g. "
                           "127.0.0.1 (default, this machine only) or its address on the lab network") from None
        if not master.is_local and is_loopback(opts.host):
            raise RosError(f"the ROS master {self.master_uri} is on another machine, which cannot reach a station "
                           "listening on loopback only: give --host ADDR, this machine's address on the lab network")
        self.timing = LoopTiming(config.period_s)
        self.reports_written = 0
        self.roscore_started = False
        self._inbox: deque[tuple[str, Any]] = deque()
        self._overflow: dict[str, int] = {}
        self._overflow_lock = threading.Lock()
        self.log = RateLimitedLog(self._emit)
        self._stop = False
        self._dump = False
        self._wall0 = 0.0
        self._wall_end: float | None = None
        self._rospy: Any = None
        self._sink: Any = None
        self._frames: dict[str, int] | None = None

    # ---------------------------------------------------------------------------------------------- callbacks
    def _offer(self, kind: str, payload: Any) -> None:
        """Called in rospy's threads: hand a message to the control loop, or count it when the inbox is full."""
        if len(self._inbox) < INBOX_MAX:
            self._inbox.append((kind, payload))
        else:
            with self._overflow_lock:
                self._overflow[kind] = self._overflow.get(kind, 0) + 1

    def on_command(self, msg: Any) -> None:
        """The ``ur3/command`` callback (any thread): the message waits in the inbox for :meth:`cycle`."""
        self._offer("command", msg)

    def _on_spawn(self, msg: Any) -> None:
        self._offer("spawn", msg.data)

    def _on_remove(self, msg: Any) -> None:
        self._offer("remove", msg.data)

    def _emit(self, level: str, text: str) -> None:
        rospy = self._rospy
        if rospy is None:
            self.out(text)
        else:
            {"info": rospy.loginfo, "warn": rospy.logwarn}.get(level, rospy.logerr)(text)

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
                self.log.log(_TOPIC_LOG[kind], "error", reason)
        for _ in range(len(self._inbox)):
            kind, payload = self._inbox.popleft()
            if kind == "command":
                try:
                    self.driver.submit(payload.destination, payload.v, payload.a, payload.io_0)
                except CommandError as exc:
                    self.log.log(_TOPIC_LOG[kind], "error", str(exc))
            elif kind == "spawn":
                n = self.station.n_towers
                if isinstance(payload, int) and 1 <= payload <= n:
                    self.world.spawn(payload - 1)
                    self.log.log(_TOPIC_LOG[kind], "info", f"{self.world.n_blocks} blocks respawned on tower {payload}")
                else:
                    self.log.log(_TOPIC_LOG[kind], "error", f"tower {payload!r} is invalid: expected 1..{n}")
            else:
                n = self.world.n_blocks
                if isinstance(payload, int) and 1 <= payload <= n:
                    what = self.world.remove(payload - 1)
                    self.log.log(_TOPIC_LOG[kind], "warn", f"block {payload} {what}")
                else:
                    self.log.log(_TOPIC_LOG[kind], "error", f"block {payload!r} is invalid: expected 1..{n}")
        self.log.flush()

    def cycle(self) -> None:
        """One control period of the node, without ROS: handle the inbox, then one driver and world step."""
        self._drain()
        self.driver.cycle()

    def _signal(self, signum: int, _frame: FrameType | None) -> None:
        if signum == signal.SIGUSR1:
            self._dump = True
        else:
            self._stop = True

    # ------------------------------------------------------------------------------------------------ report
    def report(self) -> dict[str, Any]:
        """The JSON report (see the module docstring); numbering from 1."""
        w, st = self.world, self.station
        suction_kinds = {"suction_on", "suction_off", "grasp", "release"}
        events = [e.as_dict() for e in w.events]  # the last EVENTS_KEPT; counts of all in "event_counts"
        wall = (self._wall_end or time.perf_counter()) - self._wall0 if self._wall0 else 0.0
        holding = w.holding
        return {
            "station": {"name": st.name, "calibration": st.source, "sha256": st.sha256},
            "suction": w.cup.profile.as_dict(),
            "master_uri": self.master_uri,
            "roscore_started": self.roscore_started,
            "blocks": w.n_blocks,
            "start_tower": self.options.start + 1,
            "wall_time_s": round(wall, 3),
            "world_time_s": round(w.time, 3),
            "control": self.timing.as_dict(wall),
            "commands": self.driver.summary(),
            "executed": [m.as_dict() for m in self.driver.executed],
            "rejected": [r.as_dict() for r in self.driver.rejected],
            "suction_events": [e for e in events if e["kind"] in suction_kinds],
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
            "frames": self._frames if self._frames is not None else (
                None if self._sink is None else {"rendered": self._sink.rendered, "dropped": self._sink.dropped}),
            "reports_written": self.reports_written + 1,
        }

    def write_report(self) -> dict[str, Any]:
        """Write :meth:`report` to ``options.report`` (atomically) or print it on stdout; returns it."""
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
    def run(self) -> dict[str, Any]:
        """Start (or use) the master, run the node until SIGINT/SIGTERM or ``duration_s``; returns the report."""
        from ur3hanoi.ros.env import import_rospy, import_std_msgs
        from ur3hanoi.ros.master import RosCore, listen_env
        from ur3hanoi.ros.msgs import load_messages

        msgs = load_messages()
        rospy = self._rospy = import_rospy()
        std_msgs = import_std_msgs()
        handled = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
        previous = {s: signal.signal(s, self._signal) for s in handled}
        # rospy's receiving threads hold the GIL for each message they decode: with the default 5 ms switch
        # interval a flood of messages can keep the control loop waiting most of an 8 ms period.
        switch = sys.getswitchinterval()
        sys.setswitchinterval(min(switch, 0.0005))
        sink: Any = None
        try:
            sink = self._sink = self._open_sink()  # before rospy starts its threads
            with RosCore(self.master_uri, host=self.options.host) as core:
                self.roscore_started = core.started
                # rospy reads these from the environment: the master, and the address to bind and advertise.
                env = listen_env(dict(os.environ, ROS_MASTER_URI=self.master_uri), self.options.host)
                os.environ.pop("ROS_HOSTNAME", None)
                os.environ.update(env)
                rospy.init_node("ur3hanoi_station", argv=[sys.argv[0]], disable_signals=True)
                pub_pos = rospy.Publisher("/ur3/position", msgs.position, queue_size=10)
                pub_grip = rospy.Publisher("/ur3/gripper_input", msgs.gripper_input, queue_size=10)
                rospy.Subscriber("/ur3/command", msgs.command, self.on_command, queue_size=100)
                rospy.Subscriber("/ur3hanoi/spawn", std_msgs.Int32, self._on_spawn, queue_size=10)
                rospy.Subscriber("/ur3hanoi/remove_block", std_msgs.Int32, self._on_remove, queue_size=10)
                try:
                    self._loop(msgs, pub_pos, pub_grip, sink)
                finally:
                    self._wall_end = time.perf_counter()
                    self.log.flush(force=True)
                    rospy.signal_shutdown("ur3hanoi ros-station stopped")
                if sink is not None:
                    self._frames = sink.close()
                report = self.write_report()
        finally:
            if sink is not None:
                sink.close()
            for s, handler in previous.items():
                signal.signal(s, handler)
            sys.setswitchinterval(switch)
        return report

    def _open_sink(self) -> Any:
        opts = self.options
        if opts.frames is None and opts.video is None:
            return None
        from ur3hanoi.ros.render import FrameProcess

        return FrameProcess(opts.calibration, self.world.n_blocks, opts.frames, opts.video)

    def _loop(self, msgs: Any, pub_pos: Any, pub_grip: Any, sink: Any) -> None:
        w, opts = self.world, self.options
        period = w.config.period_s
        frame_dt = 1.0 / sink.fps if sink is not None else math.inf
        next_frame = 0.0
        st = self.station
        spawned = w.n_blocks - len(w.removed)  # --remove-block leaves one out
        self.out(f"{READY_LINE} on {self.master_uri}: {st.name}, {spawned} blocks on tower {opts.start + 1}, "
                 f"{1.0 / period:g} Hz, suction profile {w.cup.profile.name} (pid {os.getpid()})")
        # Everything built so far lives as long as the node: keep the cyclic collector from scanning it in the loop.
        gc.collect()
        gc.freeze()
        self._wall0 = next_t = time.perf_counter()
        while not self._stop and not self._rospy.is_shutdown():
            now = time.perf_counter()
            self.timing.add(now - next_t)
            self.cycle()
            fb = w.feedback()
            pub_pos.publish(msgs.position(position=[float(x) for x in w.q], isReady=self.driver.ready))
            pub_grip.publish(msgs.gripper_input(DIGIN=fb.digin, AIN0=fb.ain0, AIN1=0.0))
            if sink is not None and w.time + 1e-9 >= next_frame:
                sink.offer(w.scene.data.qpos)
                next_frame += frame_dt
            if self._dump:
                self._dump = False
                self.write_report()
            if opts.duration_s is not None and now - self._wall0 >= opts.duration_s:
                break
            next_t += period
            delay = next_t - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
