"""``ur3hanoi ros2-station``: the MuJoCo station as the ROS 2 course bridge (UMD ENME480 style), without ROS.

Topics (``../shared/lab/ros2-interface.md``), every endpoint with ROS 2's default QoS:

- subscribes ``ur3e/command`` (``CommandUR3e``): a ``destination`` whose length is not 6 is dropped with a log
  line, as the bridge does; so is one with a non-finite angle or one outside the joint limits (what a controller
  would refuse). Joint values are in the **course convention** (the bridge adds ``pi/2`` to joint 1 and
  subtracts ``pi/2`` from joint 4 on the way to the controller; :mod:`ur3hanoi.convention`), or the controller's
  with ``convention="controller"``.
- publishes ``ur3e/position`` (``PositionUR3e``, same convention), ``ur3e/gripper_input`` (``GripperInput``:
  ``dig_in``/``a_in0`` from the suction model at the station's suction profile, ``a_in1`` = 0: what the course
  simulator lacks) and ``gripper/grasping`` (``std_msgs/Bool``: a block is held), every control period.

Timing: ``bridge`` (default) is the course bridge's: ``v`` and ``a`` ignored, every move one trajectory point
2.0 s away (executed as a synchronised triangular profile lasting 2.0 s, longer only when the UR3e's speed
limits demand it), no motion when only the suction changes, ``is_ready`` always true. ``honest`` executes each
command as the UR controller's ``movej`` at the message's ``v``/``a`` (capped at the robot's limits) and
``is_ready`` says whether the arm has arrived, as ``ros-station`` does.

The world, command checks, motion and suction are the ROS 1 station's (:mod:`ur3hanoi.ros.world`,
:mod:`ur3hanoi.ros.driver`, :mod:`ur3hanoi.ros.command`, :mod:`ur3hanoi.ros.movej`); only the transport
(:mod:`ur3hanoi.ros2.dds`) differs. The JSON report (SIGINT/SIGTERM, ``duration_s``; SIGUSR1 without stopping)
has the same sections as ``ros-station``'s plus ``transport``.
"""

from __future__ import annotations

import gc
import json
import math
import os
import signal
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import FrameType
from typing import Any

import numpy as np

from ur3hanoi.convention import from_controller, to_controller
from ur3hanoi.ros.errors import CommandError, RosError

READY_LINE = "ur3hanoi ros2-station: ready"
"""Printed (and flushed) on stdout once the node is up: scripts wait for it."""
NODE_NAME = "ur3hanoi_station"
BRIDGE_MOVE_S = 2.0
"""The course bridge's ``time_from_start`` of every move [s]."""
TIMINGS: tuple[str, ...] = ("bridge", "honest")

TOPIC_COMMAND = "ur3e/command"
TOPIC_POSITION = "ur3e/position"
TOPIC_GRIPPER = "ur3e/gripper_input"
TOPIC_GRASPING = "gripper/grasping"


@dataclass(frozen=True)
class Ros2StationOptions:
    """What ``ur3hanoi ros2-station`` runs (0-based towers/heights/grasps; the CLI numbers from 1).

    Attributes:
        calibration: station calibration file or shipped name (default ``ur3e_sim``).
        start, n_blocks, removed, drop_on_grasp, seed, rate_hz, report, duration_s: as for ``ros-station``.
        timing: ``bridge`` (fixed 2 s moves, ``is_ready`` always true) or ``honest`` (``movej`` at ``v``/``a``).
        convention: joint convention on the topics: ``course`` (the bridge's) or ``controller``.
        network: ``loopback`` (default), ``lab`` or an interface name (:func:`ur3hanoi.ros2.dds.cyclone_config`).
        domain_id: ROS_DOMAIN_ID (None: the environment's, default 0).
        suction_profile: a named suction profile replacing the calibration's, or None.
    """

    calibration: str = "ur3e_sim"
    start: int = 0
    n_blocks: int | None = None
    removed: int | None = None
    drop_on_grasp: int | None = None
    seed: int = 0
    rate_hz: float = 125.0
    report: Path | None = None
    duration_s: float | None = None
    timing: str = "bridge"
    convention: str = "course"
    network: str = "loopback"
    domain_id: int | None = None
    suction_profile: str | None = None


def bridge_speed(start: np.ndarray, destination: np.ndarray, duration_s: float = BRIDGE_MOVE_S
                 ) -> tuple[float, float]:
    """(v [rad/s], a [rad/s^2]) whose synchronised triangular ``movej`` from ``start`` to ``destination`` lasts
    ``duration_s``: the leading joint travels D in a triangle, v = 2 D / T, a = 4 D / T^2 (any v, a > 0 for a
    zero-length move)."""
    dist = float(np.max(np.abs(np.asarray(destination) - np.asarray(start))))
    if dist <= 1e-12:
        return 1.0, 1.0
    return 2.0 * dist / duration_s, 4.0 * dist / (duration_s * duration_s)


class Ros2Station:
    """The ``ros2-station`` node (see the module docstring). :meth:`run` blocks until stopped.

    Args:
        options: what to run.
        out: where the ready line and the report go (default: print to stdout, flushed).
        log: where log lines go (default: stderr).
    """

    def __init__(self, options: Ros2StationOptions, out: Callable[[str], None] | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.ros.driver import StationDriver
        from ur3hanoi.ros.station import LoopTiming
        from ur3hanoi.ros.world import StationWorld, WorldConfig
        from ur3hanoi.ros2.dds import domain_id_from_env
        from ur3hanoi.station import load_station, with_suction_profile

        self.options = opts = options
        self.out = out if out is not None else (lambda s: print(s, flush=True))
        self.log = log if log is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        if opts.timing not in TIMINGS:
            raise RosError(f"timing {opts.timing!r} is invalid: expected one of {', '.join(TIMINGS)}")
        if opts.convention not in ("course", "controller"):
            raise RosError(f"convention {opts.convention!r} is invalid: expected course or controller")
        self.station = load_station(opts.calibration)
        if opts.suction_profile is not None:
            self.station = with_suction_profile(self.station, opts.suction_profile)
        n_blocks = self.station.n_heights if opts.n_blocks is None else opts.n_blocks
        if not 1 <= n_blocks <= self.station.n_heights:
            raise RosError(f"{n_blocks} blocks is invalid: expected 1..{self.station.n_heights} (the grid's heights)")
        if not (math.isfinite(opts.rate_hz) and 50.0 <= opts.rate_hz <= 500.0):
            raise RosError(f"rate {opts.rate_hz} Hz is invalid: expected 50..500 Hz (the period a multiple of 2 ms)")
        try:
            self.domain_id = domain_id_from_env() if opts.domain_id is None else opts.domain_id
        except ValueError as exc:
            raise RosError(str(exc)) from None
        config = WorldConfig(period_s=1.0 / opts.rate_hz, seed=opts.seed)
        self.world = StationWorld(self.station, opts.start, n_blocks, opts.removed, config, opts.drop_on_grasp)
        self.driver = StationDriver(self.world)
        self.timing = LoopTiming(config.period_s)
        self.reports_written = 0
        self.received = 0
        self._stop = False
        self._dump = False
        self._wall0 = 0.0
        self._wall_end: float | None = None
        self._node: Any = None

    # ---------------------------------------------------------------------------------------------- commands
    def handle(self, destination: Any, v: float, a: float, io_0: bool) -> bool:
        """One ``ur3e/command``: convert, check and queue it (True), or log why it is dropped (False)."""
        self.received += 1
        values = list(destination)
        try:
            if len(values) != 6:
                raise CommandError(f"destination has {len(values)} values: expected 6 joint angles [rad]")
            q = to_controller(np.array(values, dtype=float), self.options.convention)
            if self.options.timing == "bridge":
                w, queue = self.world, self.driver.queue
                start = np.array(queue[-1].destination) if queue else w.target
                v, a = bridge_speed(start, q)
            self.driver.submit(q.tolist(), v, a, io_0)
        except CommandError as exc:
            self.log(f"[ERROR] {TOPIC_COMMAND} dropped, the arm does not move: {exc}")
            return False
        return True

    @property
    def is_ready(self) -> bool:
        """``is_ready``: always true with the bridge's timing; the arm has arrived with ``honest``."""
        return True if self.options.timing == "bridge" else self.driver.ready

    def position(self) -> list[float]:
        """The published joint angles [rad] in the topic's convention."""
        return [float(x) for x in from_controller(self.world.q, self.options.convention)]

    # ------------------------------------------------------------------------------------------------ report
    def report(self) -> dict[str, Any]:
        """The JSON report: numbering from 1 (see the module docstring)."""
        w, st = self.world, self.station
        suction_kinds = {"suction_on", "suction_off", "grasp", "release"}
        events = [e.as_dict() for e in w.events]
        wall = (self._wall_end or time.perf_counter()) - self._wall0 if self._wall0 else 0.0
        holding = w.holding
        opts = self.options
        return {
            "station": {"name": st.name, "calibration": st.source, "sha256": st.sha256, "robot": st.robot.name},
            "suction": w.cup.profile.as_dict(),
            "transport": {"middleware": "ros2 (cyclonedds)", "node": NODE_NAME, "domain_id": self.domain_id,
                          "network": opts.network, "timing": opts.timing, "convention": opts.convention,
                          "received": self.received},
            "blocks": w.n_blocks,
            "start_tower": opts.start + 1,
            "wall_time_s": round(wall, 3),
            "world_time_s": round(w.time, 3),
            "control": self.timing.as_dict(wall),
            "commands": self.driver.summary(),
            "executed": [m.as_dict() for m in self.driver.executed],
            "rejected": [r.as_dict() for r in self.driver.rejected],
            "suction_events": [e for e in events if e["kind"] in suction_kinds],
            "faults": [e for e in events if e["kind"] in ("removed", "dropped")],
            "final": {
                "q": [round(float(x), 9) for x in w.q],
                "suction_on": w.suction_on,
                "holding": None if holding is None else holding + 1,
                "at_home": w.at_home(),
                "blocks": [b.as_dict() for b in w.blocks()],
            },
            "reports_written": self.reports_written + 1,
        }

    def write_report(self) -> dict[str, Any]:
        """Write :meth:`report` to ``options.report`` (atomically) or print it; returns it."""
        from ur3hanoi.io.atomic import atomic_write

        report = self.report()
        text = json.dumps(report, indent=1) + "\n"
        self.reports_written += 1
        if self.options.report is not None:
            atomic_write(self.options.report, text)
        else:
            self.out(text.rstrip("\n"))
        return report

    def _signal(self, signum: int, _frame: FrameType | None) -> None:
        if signum == signal.SIGUSR1:
            self._dump = True
        else:
            self._stop = True

    # --------------------------------------------------------------------------------------------------- run
    def run(self) -> dict[str, Any]:
        """Create the node, run until SIGINT/SIGTERM or ``duration_s``; returns the final report."""
        from ur3hanoi.ros2.dds import Ros2Node
        from ur3hanoi.ros2.msgs import Bool, CommandUR3e, GripperInput, PositionUR3e

        handled = (signal.SIGINT, signal.SIGTERM, signal.SIGUSR1)
        previous = {s: signal.signal(s, self._signal) for s in handled}
        try:
            try:
                node = self._node = Ros2Node(NODE_NAME, self.domain_id, self.options.network)
            except Exception as exc:  # the DDS library's own errors (bad interface, no free participant index)
                raise RosError(f"cannot start the DDS participant on network {self.options.network!r}: {exc}") \
                    from None
            commands = node.subscription(TOPIC_COMMAND, CommandUR3e)
            pubs = (node.publisher(TOPIC_POSITION, PositionUR3e), node.publisher(TOPIC_GRIPPER, GripperInput),
                    node.publisher(TOPIC_GRASPING, Bool))
            node.announce()
            try:
                self._loop(commands, pubs, (PositionUR3e, GripperInput, Bool))
            finally:
                self._wall_end = time.perf_counter()
                node.close()
            return self.write_report()
        finally:
            for s, handler in previous.items():
                signal.signal(s, handler)

    def _loop(self, commands: Any, pubs: tuple[Any, Any, Any], types: tuple[Any, Any, Any]) -> None:
        w, opts = self.world, self.options
        pub_pos, pub_grip, pub_grasp = pubs
        Position, Gripper, Bool = types
        period = w.config.period_s
        st = self.station
        self.out(f"{READY_LINE} on ROS_DOMAIN_ID {self.domain_id} ({opts.network}): {st.name} ({st.robot.title}), "
                 f"{w.n_blocks} blocks on tower {opts.start + 1}, {1.0 / period:g} Hz, {opts.timing} timing, "
                 f"{opts.convention} convention, suction profile {w.cup.profile.name} (pid {os.getpid()})")
        gc.collect()
        gc.freeze()
        self._wall0 = next_t = time.perf_counter()
        max_per_cycle = 50  # a flood is drained over several cycles, never stalls the loop
        while not self._stop:
            now = time.perf_counter()
            self.timing.add(now - next_t)
            for msg in commands.take(N=max_per_cycle):
                if not hasattr(msg, "destination"):  # an invalid sample (instance state only)
                    continue
                self.handle(msg.destination, msg.v, msg.a, msg.io_0)
            self.driver.cycle()
            fb = w.feedback()
            pub_pos.write(Position(position=self.position(), is_ready=self.is_ready))
            pub_grip.write(Gripper(dig_in=int(fb.digin), a_in0=float(fb.ain0), a_in1=0.0))
            pub_grasp.write(Bool(data=bool(fb.held)))
            if self._dump:
                self._dump = False
                self.write_report()
            if opts.duration_s is not None and now - self._wall0 >= opts.duration_s:
                break
            next_t += period
            delay = next_t - time.perf_counter()
            if delay > 0:
                time.sleep(delay)
