"""``ur3hanoi ros2-station``: the MuJoCo station as the ROS 2 course bridge (UMD ENME480 style), without ROS.

Topics (``../shared/lab/ros2-interface.md``), every endpoint with ROS 2's default QoS:

- subscribes ``ur3e/command`` (``CommandUR3e``): a ``destination`` whose length is not 6 is dropped with a log
  line, as the bridge does; so is one with a non-finite angle or one outside the joint limits (what a controller
  would refuse). Joint values are in the **course convention** (the bridge adds ``pi/2`` to joint 1 and
  subtracts ``pi/2`` from joint 4 on the way to the controller; :mod:`ur3hanoi.robot.convention`), or the controller's
  with ``convention="controller"``.
- publishes ``ur3e/position`` (``PositionUR3e``, same convention), ``ur3e/gripper_input`` (``GripperInput``:
  ``dig_in``/``a_in0`` from the suction model at the station's suction profile, ``a_in1`` = 0: what the course
  simulator lacks) and ``gripper/grasping`` (``std_msgs/Bool``: a block is held), every control period.
- subscribes ``ur3hanoi/spawn`` (``std_msgs/Int32``, tower 1..3: respawn every block there, like
  ``lab2_spawn.py``) and ``ur3hanoi/remove_block`` (``std_msgs/Int32``, block 1..n, 1 = bottom: take it away; a
  held block is dropped), as ``ros-station`` does; an invalid number is refused with a log line.

Timing: ``bridge`` (default) is the course bridge's: ``v`` and ``a`` ignored, every move one trajectory point
2.0 s away (executed as a synchronised triangular profile lasting 2.0 s, longer only when the UR3e's speed
limits demand it), no motion when only the suction changes, ``is_ready`` always true. ``honest`` executes each
command as the UR controller's ``movej`` at the message's ``v``/``a`` (capped at the robot's limits) and
``is_ready`` says whether the arm has arrived, as ``ros-station`` does.

The world, command checks, motion, suction, the real-time loop, the bounded inbox, rate-limited log lines and
the report are the transport-neutral station's (:class:`ur3hanoi.interface.common.station.ServerCore`), shared with
``ros-station``; only the transport (:mod:`ur3hanoi.interface.ros2.dds`) differs: the loop takes at most 50 messages a
cycle from each DDS reader (whose history is itself bounded by the QoS depth). Refusals are logged at most once
a second per topic, with counts. The JSON report (SIGINT/SIGTERM, ``duration_s``; SIGUSR1 without stopping)
has ``ros-station``'s sections plus ``transport``.

``--frames``/``--video`` render in a separate low-priority process that drops frames rather than stall the loop
(:meth:`~ur3hanoi.interface.common.station.ServerCore.rendering`, as ``ros-station``); the report's ``frames`` counts
them.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from dataclasses import dataclass
from types import SimpleNamespace
from typing import Any, ClassVar

import numpy as np

from ur3hanoi.errors import InputError
from ur3hanoi.interface.common.station import ServerOptions
from ur3hanoi.interface.course.station import CourseStation
from ur3hanoi.interface.ros2.errors import DdsError
from ur3hanoi.robot.convention import from_controller, to_controller

READY_LINE = "ur3hanoi ros2-station: ready"
"""Printed (and flushed) on stdout once the node is up: scripts wait for it."""
NODE_NAME = "ur3hanoi_station"
BRIDGE_MOVE_S = 2.0
"""The course bridge's ``time_from_start`` of every move [s]."""
TIMINGS: tuple[str, ...] = ("bridge", "honest")
TAKE_PER_CYCLE = 50
"""Messages taken from each DDS reader per control cycle: a flood is drained over several cycles."""

TOPIC_COMMAND = "ur3e/command"
TOPIC_POSITION = "ur3e/position"
TOPIC_GRIPPER = "ur3e/gripper_input"
TOPIC_GRASPING = "gripper/grasping"
TOPIC_SPAWN = "ur3hanoi/spawn"
TOPIC_REMOVE = "ur3hanoi/remove_block"


@dataclass(frozen=True)
class Ros2ServerOptions(ServerOptions):
    """What ``ur3hanoi ros2-station`` runs: :class:`~ur3hanoi.interface.common.station.ServerOptions` (the calibration
    ``ur3e_sim`` by default) and

    Attributes:
        timing: ``bridge`` (fixed 2 s moves, ``is_ready`` always true) or ``honest`` (``movej`` at ``v``/``a``).
        convention: joint convention on the topics: ``course`` (the bridge's) or ``controller``.
        network: ``loopback`` (default), ``lab`` or an interface name
        (:func:`ur3hanoi.interface.ros2.dds.cyclone_config`). domain_id: ROS_DOMAIN_ID (None: the environment's, default
        0).
    """

    calibration: str = "ur3e_sim"
    timing: str = "bridge"
    convention: str = "course"
    network: str = "loopback"
    domain_id: int | None = None


def bridge_speed(start: np.ndarray, destination: np.ndarray, duration_s: float = BRIDGE_MOVE_S
                 ) -> tuple[float, float]:
    """(v [rad/s], a [rad/s^2]) whose synchronised triangular ``movej`` from ``start`` to ``destination`` lasts
    ``duration_s``: the leading joint travels D in a triangle, v = 2 D / T, a = 4 D / T^2 (any v, a > 0 for a
    zero-length move)."""
    dist = float(np.max(np.abs(np.asarray(destination) - np.asarray(start))))
    if dist <= 1e-12:
        return 1.0, 1.0
    return 2.0 * dist / duration_s, 4.0 * dist / (duration_s * duration_s)


class Ros2Server(CourseStation):
    """The ``ros2-station`` node (see the module docstring). :meth:`run` blocks until stopped.

    Args:
        options: what to run.
        out: where the ready line goes (default: print to stderr, flushed), and the report when ``report_out``
            is not given.
        log: where log lines go (default: stderr).
        report_out: where the JSON report goes without ``options.report`` (default: ``out`` when given, else
            print to stdout, flushed): stdout carries the report alone.
    """

    options: Ros2ServerOptions

    TOPIC_LOG: ClassVar[dict[str, str]] = {"command": f"{TOPIC_COMMAND} dropped, the arm does not move",
                                           "spawn": TOPIC_SPAWN, "remove": TOPIC_REMOVE}

    def __init__(self, options: Ros2ServerOptions, out: Callable[[str], None] | None = None,
                 log: Callable[[str], None] | None = None,
                 report_out: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.interface.ros2.dds import domain_id_from_env

        if options.timing not in TIMINGS:
            raise InputError(f"timing {options.timing!r} is invalid: expected one of {', '.join(TIMINGS)}")
        if options.convention not in ("course", "controller"):
            raise InputError(f"convention {options.convention!r} is invalid: expected course or controller")
        # stdout carries the JSON report alone (``station > report.json``); the ready line goes with the logs
        said = out if out is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        self._log_line = log if log is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        report = report_out if report_out is not None else out if out is not None else (lambda s: print(s, flush=True))
        super().__init__(options, said, report)
        try:
            self.domain_id = domain_id_from_env() if options.domain_id is None else options.domain_id
        except ValueError as exc:
            raise InputError(str(exc)) from None
        self.received = 0

    def _emit(self, level: str, text: str) -> None:
        self._log_line(f"[{level.upper()}] {text}")

    # ---------------------------------------------------------------------------------------------- commands
    def _command(self, msg: Any) -> None:
        """Convert one ``ur3e/command`` to the controller convention and queue it (bridge timing: a 2 s move)."""
        self.received += 1
        values = list(msg.destination)
        if len(values) != 6:
            raise self.controller.refuse(f"destination has {len(values)} values: expected 6 joint angles [rad]")
        q = to_controller(np.array(values, dtype=float), self.options.convention)
        v, a = msg.v, msg.a
        if self.options.timing == "bridge":
            queue = self.controller.queue
            start = np.array(queue[-1].destination) if queue else self.world.target
            v, a = bridge_speed(start, q)  # the bridge ignores v and a (a bad destination is named first)
        self.controller.submit(q.tolist(), v, a, msg.io_0)

    def handle(self, destination: Any, v: float, a: float, io_0: bool) -> bool:
        """One ``ur3e/command`` now: convert, check and queue it (True), or log why it is dropped (False)."""
        return self.submit_command(SimpleNamespace(destination=destination, v=v, a=a, io_0=io_0))

    @property
    def is_ready(self) -> bool:
        """``is_ready``: always true with the bridge's timing; the arm has arrived with ``honest``."""
        return True if self.options.timing == "bridge" else self.controller.ready

    def position(self) -> list[float]:
        """The published joint angles [rad] in the topic's convention."""
        return [float(x) for x in from_controller(self.world.q, self.options.convention)]

    # ------------------------------------------------------------------------------------------------ report
    def _report_transport(self) -> dict[str, Any]:
        opts = self.options
        return {"transport": {"middleware": "ros2 (cyclonedds)", "node": NODE_NAME, "domain_id": self.domain_id,
                              "network": opts.network, "timing": opts.timing, "convention": opts.convention,
                              "received": self.received}}

    # --------------------------------------------------------------------------------------------------- run
    def run(self) -> dict[str, Any]:
        """Create the node, run until SIGINT/SIGTERM or ``duration_s``; returns the final report."""
        from ur3hanoi.interface.ros2.dds import Ros2Node
        from ur3hanoi.interface.ros2.msgs import Bool, CommandUR3e, GripperInput, Int32, PositionUR3e

        with self.signals(), self.rendering():  # the rendering process starts before the DDS threads
            try:
                node = Ros2Node(NODE_NAME, self.domain_id, self.options.network)
            except Exception as exc:  # the DDS library's own errors (bad interface, no free participant index)
                raise DdsError(f"cannot start the DDS participant on network {self.options.network!r}: {exc}") \
                    from None
            try:
                commands = node.subscription(TOPIC_COMMAND, CommandUR3e)
                spawns, removals = node.subscription(TOPIC_SPAWN, Int32), node.subscription(TOPIC_REMOVE, Int32)
                pub_pos, pub_grip, pub_grasp = (node.publisher(TOPIC_POSITION, PositionUR3e),
                                                node.publisher(TOPIC_GRIPPER, GripperInput),
                                                node.publisher(TOPIC_GRASPING, Bool))
                node.announce()

                def receive() -> None:
                    for msg in commands.take(N=TAKE_PER_CYCLE):
                        if hasattr(msg, "destination"):  # not an invalid sample (instance state only)
                            self.on_command(msg)
                    for msg in spawns.take(N=TAKE_PER_CYCLE):
                        if isinstance(msg, Int32):
                            self.on_spawn(int(msg.data))
                    for msg in removals.take(N=TAKE_PER_CYCLE):
                        if isinstance(msg, Int32):
                            self.on_remove(int(msg.data))

                def publish() -> None:
                    fb = self.world.feedback()
                    pub_pos.write(PositionUR3e(position=self.position(), is_ready=self.is_ready))
                    pub_grip.write(GripperInput(dig_in=int(fb.digin), a_in0=float(fb.ain0), a_in1=0.0))
                    pub_grasp.write(Bool(data=bool(fb.held)))

                self.loop(self._ready_line(), receive, publish)
            finally:
                node.close()
            self.close_sink()  # the report has the final frame counts
            return self.write_report()

    def _ready_line(self) -> str:
        w, opts, st = self.world, self.options, self.station
        return (f"{READY_LINE} on ROS_DOMAIN_ID {self.domain_id} ({opts.network}): {st.name} ({st.robot.title}), "
                f"{w.n_blocks} blocks on tower {opts.start + 1}, {1.0 / w.config.period_s:g} Hz, {opts.timing} "
                f"timing, {opts.convention} convention, suction profile {w.cup.profile.name} (pid {os.getpid()})")
