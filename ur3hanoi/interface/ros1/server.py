"""``ur3hanoi ros-station``: a drop-in for the course's Gazebo world and ``ur3_driver``, backed by MuJoCo.

The node speaks the course's topics and messages exactly (:mod:`ur3hanoi.interface.ros1.msgs`):

- subscribes ``/ur3/command``: each accepted command runs as the controller's ``movej``
  (:mod:`ur3hanoi.robot.movej`, ``v``/``a`` capped at the UR3's limits) after the ones before it
  (:mod:`ur3hanoi.interface.course.controller`), switching the suction to ``io_0`` when it starts; malformed commands
  are refused with a logged error and no motion (:mod:`ur3hanoi.interface.course.command`);
- publishes ``/ur3/position`` (measured joint angles, ``isReady`` false while moving or not yet within
  0.0005 rad of the destination) and ``/ur3/gripper_input`` (``DIGIN`` bit 0, ``AIN0`` from the suction model)
  every control period (8 ms: 125 Hz, like the course driver);
- subscribes ``/ur3hanoi/spawn`` (``std_msgs/Int32``, tower 1..3: respawn every block there, like
  ``lab2_spawn.py``) and ``/ur3hanoi/remove_block`` (``std_msgs/Int32``, block 1..3, 1 = bottom/green: take it
  away; a held block is dropped).

Real time, the bounded inbox, rate-limited logging and the report are the transport-neutral station's
(:mod:`ur3hanoi.interface.common.station`); this module binds them to rospy. A roscore is started when none answers at
``ROS_MASTER_URI`` (:mod:`ur3hanoi.interface.ros1.master`) and stopped on exit, or when the station dies
(:mod:`ur3hanoi.interface.ros1.guard`).

The master is watched while the station runs (:class:`~ur3hanoi.interface.ros1.watch.MasterWatch`): when it is gone
(killed, crashed, stopped by someone else) the station says so on stderr within about a second and, if it had started
that master, starts it again on the same URI and registers with it again (nodes connected before keep their
connections; nodes started now find the station); a master it did not start, or one it cannot start again, stops
the station: report written, one error line, exit 2. The report's ``master_events`` records what happened.

A flood cannot stall the loop: the ROS callbacks only append to the bounded inbox
(:data:`~ur3hanoi.interface.common.inbox.INBOX_MAX` messages), log lines are rate-limited and the records bounded
(:class:`~ur3hanoi.interface.common.station.ServerCore`).

Listening: the station and the roscore it starts bind and advertise ``host`` (``ROS_IP``), by default
``127.0.0.1``: nothing on the lab network can reach them. ``--host ADDR`` (this machine's address on the lab
network) opens them; a master on another machine needs it. ``ROS_IP``/``ROS_HOSTNAME`` of the environment are
not used.

Output: the ready line and every info line go to ``info`` (the CLI: stderr); standard output carries only the
JSON report when there is no ``--report`` file.

``--frames``/``--video`` render in a separate low-priority process (:mod:`ur3hanoi.interface.common.render`, started by
:meth:`~ur3hanoi.interface.common.station.ServerCore.rendering`), which drops frames rather than stall the loop.

The JSON report (:meth:`RosServer.report`): commands executed (with duration, settle time and rest error),
refused, suction events, faults, final block positions (tower/height, or none = off-grid), loop timing, rendered
frames. It is
written on SIGINT/SIGTERM and at the end of ``--duration``, and on SIGUSR1 without stopping: to ``--report FILE``
(atomically) or, without it, to stdout.
"""

from __future__ import annotations

import ipaddress
import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

from ur3hanoi.interface.common.station import ServerCore, ServerOptions
from ur3hanoi.interface.course.station import CourseStation
from ur3hanoi.interface.ros1.errors import RosError

READY_LINE = "ur3hanoi ros-station: ready"
"""Written (and flushed) on stderr once the node is up: scripts wait for it."""
NODE_NAME = "ur3hanoi_station"
"""The station's node name (``ur3hanoi teach`` looks for it to know there is no pendant)."""


@dataclass(frozen=True)
class RosServerOptions(ServerOptions):
    """What ``ur3hanoi ros-station`` runs: :class:`~ur3hanoi.interface.common.station.ServerOptions` and

    Attributes:
        master_uri: ROS master (None: ``ROS_MASTER_URI``, else http://localhost:11311).
        host: address the station and the roscore it starts listen on and advertise (``ROS_IP``); the default
            127.0.0.1 keeps them on this machine.
    """

    master_uri: str | None = None
    host: str = "127.0.0.1"


class RosStation(ServerCore[Any]):
    """A station on rospy for either protocol: its master, guard, watch, spawn and remove topics and its loop (see
    the module docstring); a protocol's binding provides :meth:`_open` (its topics) and :meth:`_ready_detail`
    (:class:`RosServer`, :class:`ur3hanoi.interface.ros1.ur_server.RosDriverServer`). :meth:`run` blocks until
    stopped.

    Args:
        options: what to run.
        out: where the ready line and info lines go (default: print to stderr, flushed).
        report_out: where the JSON report goes without ``options.report`` (default: print to stdout, flushed).
    """

    options: RosServerOptions

    TOPIC_LOG: ClassVar[dict[str, str]] = {"command": "ur3/command rejected, the arm does not move",
                                           "spawn": "ur3hanoi/spawn", "remove": "ur3hanoi/remove_block"}

    def __init__(self, options: RosServerOptions, out: Callable[[str], None] | None = None,
                 report_out: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.interface.ros1.master import MasterUri, is_loopback, master_uri_from_env

        super().__init__(options, out if out is not None else (lambda s: print(s, file=sys.stderr, flush=True)),
                         report_out if report_out is not None else (lambda s: print(s, flush=True)))
        opts = options
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
        self.roscore_started = False
        self._rospy: Any = None
        self._core: Any = None  # the RosCore while running
        self.master_events: list[dict[str, Any]] = []
        self._master_failed: str | None = None

    # ---------------------------------------------------------------------------------------------- callbacks
    def _on_spawn(self, msg: Any) -> None:
        self.on_spawn(msg.data)

    def _on_remove(self, msg: Any) -> None:
        self.on_remove(msg.data)

    def _emit(self, level: str, text: str) -> None:
        rospy = self._rospy
        if rospy is None:
            self.out(text)
        else:
            {"info": rospy.loginfo, "warn": rospy.logwarn}.get(level, rospy.logerr)(text)

    # ------------------------------------------------------------------------------------------------ report
    def _report_transport(self) -> dict[str, Any]:
        return {"master_uri": self.master_uri, "roscore_started": self.roscore_started,
                "master_events": list(self.master_events)}

    # ------------------------------------------------------------------------------------------------ master
    def _master_event(self, event: str, **fields: Any) -> None:
        wall = self.clock.wall_s
        self.master_events.append({"wall_time_s": round(wall, 3), "event": event, **fields})

    def _master_lost(self, reason: str) -> int | None:
        """The watch thread's ``on_lost``: start the station's own master again and register with it (its pid),
        or stop the station (None)."""
        from ur3hanoi.interface.ros1.master import master_pid
        from ur3hanoi.interface.ros1.watch import forget_master, reregister

        core, uri = self._core, self.master_uri
        self._master_event("lost", reason=reason)
        if core is None or not core.started:
            forget_master()
            self._master_failed = (f"the ROS master at {uri} is gone ({reason}); the station did not start it, so it "
                                   "stops: start the master again, then the station")
            return None
        self.out(f"ur3hanoi ros-station: the ROS master at {uri} is gone ({reason}): starting it again")
        try:
            core.stop()
            core.start()
            pid = master_pid(uri)
            if pid is None:
                raise RosError("it does not answer")
        except RosError as exc:
            forget_master()
            self._master_failed = f"the ROS master at {uri} is gone ({reason}) and could not be started again: {exc}"
            return None
        registered = reregister()
        self.roscore_started = core.started
        self._master_event("restarted" if core.started else "attached", pid=pid, registered=registered)
        self.out(f"ur3hanoi ros-station: {'started the ROS master again' if core.started else 'found a ROS master'} "
                 f"at {uri} (pid {pid}) and registered {registered} topics with it")
        return pid

    # --------------------------------------------------------------------------------------------------- run
    def run(self) -> dict[str, Any]:
        """Start (or use) the master, run the node until SIGINT/SIGTERM or ``duration_s``; returns the report."""
        from ur3hanoi.interface.ros1.env import import_rospy, import_std_msgs
        from ur3hanoi.interface.ros1.master import RosCore, listen_env, master_pid
        from ur3hanoi.interface.ros1.watch import MasterWatch, quick_shutdown

        rospy = self._rospy = import_rospy()
        std_msgs = import_std_msgs()
        # rospy's receiving threads hold the GIL for each message they decode: with the default 5 ms switch
        # interval a flood of messages can keep the control loop waiting most of an 8 ms period.
        switch = sys.getswitchinterval()
        sys.setswitchinterval(min(switch, 0.0005))
        try:
            # The rendering process starts before rospy's threads.
            with self.signals(), self.rendering(), RosCore(self.master_uri, host=self.options.host) as core:
                self._core, self.roscore_started = core, core.started
                # rospy reads these from the environment: the master, and the address to bind and advertise.
                env = listen_env(dict(os.environ, ROS_MASTER_URI=self.master_uri), self.options.host)
                os.environ.pop("ROS_HOSTNAME", None)
                os.environ.update(env)
                rospy.init_node(NODE_NAME, argv=[sys.argv[0]], disable_signals=True)
                quick_shutdown()
                publish = self._open(rospy)
                rospy.Subscriber("/ur3hanoi/spawn", std_msgs.Int32, self._on_spawn, queue_size=10)
                rospy.Subscriber("/ur3hanoi/remove_block", std_msgs.Int32, self._on_remove, queue_size=10)
                try:
                    with MasterWatch(self.master_uri, master_pid(self.master_uri) or 0, self._master_lost):
                        self._run_loop(publish)
                finally:
                    rospy.signal_shutdown("ur3hanoi ros-station stopped")
                self.close_sink()  # the report has the final frame counts
                report = self.write_report()
        finally:
            sys.setswitchinterval(switch)
            self._core = None
        if self._master_failed is not None:
            raise RosError(self._master_failed)
        return report

    def _run_loop(self, publish: Callable[[], None]) -> None:
        w, opts = self.world, self.options
        st = self.station
        spawned = w.n_blocks - len(w.removed)  # --remove-block leaves one out
        ready = (f"{READY_LINE} on {self.master_uri}: {st.name}, {spawned} blocks on tower {opts.start + 1}, "
                 f"{self._ready_detail()} (pid {os.getpid()})")
        # The ROS callbacks fill the inbox in rospy's threads: nothing to receive here.
        self.loop(ready, lambda: None, publish,
                  running=lambda: self._master_failed is None and not self._rospy.is_shutdown())

    def _open(self, rospy: Any) -> Callable[[], None]:
        """Advertise and subscribe the protocol's topics; returns the publish step of every control cycle."""
        raise NotImplementedError

    def _ready_detail(self) -> str:
        """What the ready line says after the station's name and blocks."""
        raise NotImplementedError


class RosServer(RosStation, CourseStation):
    """The ``ros-station`` node of the course's topics (see the module docstring). :meth:`run` blocks until stopped.

    Args:
        options: what to run.
        out: where the ready line and info lines go (default: print to stderr, flushed).
        report_out: where the JSON report goes without ``options.report`` (default: print to stdout, flushed).
    """

    def _open(self, rospy: Any) -> Callable[[], None]:
        """Advertise and subscribe the course's topics; returns the publish step of every control cycle."""
        from ur3hanoi.interface.ros1.msgs import load_messages

        msgs = load_messages()
        w = self.world
        pub_pos = rospy.Publisher("/ur3/position", msgs.position, queue_size=10)
        pub_grip = rospy.Publisher("/ur3/gripper_input", msgs.gripper_input, queue_size=10)
        rospy.Subscriber("/ur3/command", msgs.command, self.on_command, queue_size=100)

        def publish() -> None:
            fb = w.feedback()
            pub_pos.publish(msgs.position(position=[float(x) for x in w.q], isReady=self.controller.ready))
            pub_grip.publish(msgs.gripper_input(DIGIN=fb.digin, AIN0=fb.ain0, AIN1=0.0))

        return publish

    def _ready_detail(self) -> str:
        """What the ready line says after the station's name and blocks."""
        w = self.world
        return f"{1.0 / w.config.period_s:g} Hz, suction profile {w.cup.profile.name}"
