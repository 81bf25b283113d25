"""``ur3hanoi ros2-station --driver ur``: the MuJoCo station behind the official UR ROS 2 driver's interface, on rclpy.

What a client of ``ur_robot_driver`` finds (:mod:`ur3hanoi.interface.ros2.ur_driver` has the names per distribution):

- ``/joint_states`` (``sensor_msgs/JointState``, every control cycle). The ROS 2 driver guarantees no joint order
  (ros2_controllers #159): the station publishes the ROS 1 driver's alphabetical order, so a client that indexes by
  position fails here as it would on a robot;
- the trajectory controller's ``follow_joint_trajectory`` action (``control_msgs/action/FollowJointTrajectory``, an
  rclpy ``ActionServer``): a goal the controller's ``validate_trajectory_msg`` refuses is **rejected at send_goal**,
  without a result or a code (the reason goes to the log); an accepted goal preempts the running one (aborted with
  INVALID_GOAL and the controller's text); the trajectory is followed by the controller of
  :class:`~ur3hanoi.interface.urdriver.station.DriverStation` (interpolation, speed scaling, path and goal tolerances;
  goal time 0: no goal-time abort); a cancel of the running goal is accepted, the goal ends canceled and the arm
  holds; feedback at the controller's ``action_monitor_rate`` (20 Hz);
- ``/io_and_status_controller/set_io`` (``ur_msgs/srv/SetIO``): answers once the output changed, polling every 50 ms
  up to 10 times as the driver's GPIO controller does (``false`` after that, or for a request the driver refuses);
  ``/io_and_status_controller/io_states`` (``ur_msgs/msg/IOStates``, every cycle), with the suction model's feedback
  on the calibration's pins;
- ``/speed_scaling_state_broadcaster/speed_scaling`` (``std_msgs/msg/Float64``, **percent**, 100 Hz);
- ``/io_and_status_controller/robot_program_running`` (``std_msgs/msg/Bool``, transient local, on change). While the
  External Control program is stopped (``--program-stop-at`` .. ``--program-resume-at``) the trajectory controller
  is inactive, as the driver's ``controller_stopper`` leaves it: the running goal is aborted (INVALID_GOAL, "Current
  goal cancelled during deactivate transition."), new goals are rejected at send_goal ("Can't accept new action
  goals. Controller is not running." in the log);
- ``/controller_manager/list_controllers`` and ``/controller_manager/switch_controller`` (``controller_manager_msgs``)
  over the driver's controllers (:mod:`~ur3hanoi.interface.urdriver.controllers`), with a ``follow_joint_trajectory``
  action for each trajectory controller (scaled, plain, passthrough): only the active one accepts goals, and all
  drive the same simulated controller (the passthrough controller's own interpolation on the robot and its result
  texts are not modelled); ``/dashboard_client/play``, ``stop`` (``std_srvs/Trigger``) and ``program_running``
  (``ur_dashboard_msgs/IsProgramRunning``) start, stop and report the program
  (:mod:`~ur3hanoi.interface.urdriver.services`).

Besides: ``ur3hanoi/spawn`` and ``ur3hanoi/remove_block`` (``std_msgs/Int32``) as on the course station, and
``ur3hanoi/hold_arm`` (``std_msgs/Float64`` seconds: the arm is held, e.g. to provoke a path-tolerance abort).

Threads: the control loop runs in the main thread on the wall clock (:meth:`ServerCore.loop
<ur3hanoi.interface.common.station.ServerCore.loop>`); rclpy's executor runs the callbacks in a thread pool, and they
only hand work to the station's inbox or wait for what the loop publishes. Loopback only
(``ROS_AUTOMATIC_DISCOVERY_RANGE`` LOCALHOST) unless ``network="lab"``.
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable, Hashable
from dataclasses import dataclass
from typing import Any, ClassVar

from ur3hanoi.errors import InputError
from ur3hanoi.interface.ros2.ur_driver import goal_from_msg, names_for, preempted_text, profile_for
from ur3hanoi.interface.urdriver.facts import ErrorCode
from ur3hanoi.interface.urdriver.follower import Outcome
from ur3hanoi.interface.urdriver.goal import check_goal
from ur3hanoi.interface.urdriver.profile import NOT_RUNNING
from ur3hanoi.interface.urdriver.services import ServiceCall
from ur3hanoi.interface.urdriver.station import DriverStation, DriverStationOptions

READY_LINE = "ur3hanoi ros2-station: ready"
NODE_NAME = "ur3hanoi_ur_driver"
SET_IO_POLL_S = 0.05
SET_IO_RETRIES = 10
"""The GPIO controller's check of a write: every 50 ms, ``check_io_successfull_retries`` = 10 times."""
NETWORKS = ("loopback", "lab")


@dataclass(frozen=True)
class Ros2DriverOptions(DriverStationOptions):
    """What ``ros2-station --driver ur`` runs: :class:`DriverStationOptions` and the ROS 2 ``distro`` (names and
    controller rules), ``network`` (``loopback`` or ``lab``), ``domain_id`` (None: ``$ROS_DOMAIN_ID``, else 0)."""

    calibration: str = "ur3e_sim"
    distro: str = "jazzy"
    network: str = "loopback"
    domain_id: int | None = None


class _Goal:
    """One accepted goal: its rclpy handle and, once the loop has it, how it ended."""

    def __init__(self, handle: Any) -> None:
        self.handle = handle
        self.ended = threading.Event()
        self.outcome: Outcome | None = None
        self.last_feedback = 0.0


def _key(goal_handle: Any) -> str:
    return bytes(goal_handle.goal_id.uuid).hex()


class Ros2DriverStation(DriverStation):
    """The ``ros2-station --driver ur`` node (see the module docstring). :meth:`run` blocks until stopped."""

    options: Ros2DriverOptions

    TOPIC_LOG: ClassVar[dict[str, str]] = {**DriverStation.TOPIC_LOG, "spawn": "ur3hanoi/spawn",
                                           "remove": "ur3hanoi/remove_block", "hold": "ur3hanoi/hold_arm"}

    def __init__(self, options: Ros2DriverOptions, out: Callable[[str], None] | None = None,
                 log: Callable[[str], None] | None = None,
                 report_out: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.interface.ros2.distros import ROS_DISTROS

        if options.distro not in ROS_DISTROS:
            raise InputError(f"ROS 2 distribution {options.distro!r} is invalid: expected one of "
                             f"{', '.join(ROS_DISTROS)}")
        if options.network not in NETWORKS:
            raise InputError(f"network {options.network!r} is invalid with the UR driver's interface (rclpy): "
                             f"expected {' or '.join(NETWORKS)}")
        if options.profile.validation != "ros2" or options.initial_controller is None:
            from dataclasses import replace

            options = replace(options, profile=profile_for(options.distro),
                              initial_controller=names_for(options.distro).follow_joint_trajectory.split("/")[1])
        # stdout carries the JSON report alone (``station > report.json``); the ready line goes with the logs
        said = out if out is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        self._log_line = log if log is not None else (lambda s: print(s, file=sys.stderr, flush=True))
        report = report_out if report_out is not None else out if out is not None else (lambda s: print(s, flush=True))
        super().__init__(options, said, report)
        self.names = names_for(options.distro)
        self._goals: dict[Hashable, _Goal] = {}
        self._lock = threading.Lock()
        self._stopping = False
        self.rejected_at_send_goal = 0
        self.domain_id = options.domain_id

    def _emit(self, level: str, text: str) -> None:
        self._log_line(f"[{level.upper()}] {text}")

    # ------------------------------------------------------------------------------------------ the action
    def goal_callback(self, request: Any, now_s: float, controller: str) -> bool:
        """Accept (True) or reject at send_goal (False, the reason logged) as ``validate_trajectory_msg`` does; a
        goal to ``controller`` while it is not the active trajectory controller (or the program is stopped) is
        rejected as an inactive controller rejects it."""
        goal = goal_from_msg(request, now_s)
        why = check_goal(goal, self.options.profile)
        active = self.program_running and self.controllers.trajectory_controller() == controller
        reason = NOT_RUNNING if not active else None if why is None else why.reason
        if reason is not None:
            self.rejected_at_send_goal += 1
            self.log.log(self.TOPIC_LOG["goal"], "error", f"goal rejected at send_goal: {reason}")
            return False
        return True

    def accepted(self, handle: Any, now_s: float) -> None:
        """An accepted goal: to the controller (it preempts the running one at the next cycle)."""
        key = _key(handle)
        with self._lock:
            self._goals[key] = _Goal(handle)
        self.on_goal(key, goal_from_msg(handle.request, now_s))

    def execute(self, handle: Any, action: Any) -> Any:
        """Wait until the loop says how the goal ended; set its state and return its result."""
        goal = self._goals[_key(handle)]
        goal.ended.wait()
        result = action.Result()
        o = goal.outcome
        if o is None:  # the station stops
            result.error_code, result.error_string = int(ErrorCode.INVALID_GOAL), "The station stopped."
            handle.abort()
        elif o.status == "succeeded":
            result.error_code, result.error_string = int(o.code), o.error_string
            handle.succeed()
        elif o.status == "canceled":
            handle.canceled()
        else:
            text = preempted_text(self.options.distro) if o.status == "preempted" else o.error_string
            code = ErrorCode.INVALID_GOAL if o.status == "preempted" else o.code
            result.error_code, result.error_string = int(code), text
            handle.abort()
        with self._lock:
            self._goals.pop(_key(handle), None)
        return result

    def cancel(self, handle: Any) -> None:
        """A cancel request: the controller ends the goal if it is the running one (the driver accepts every
        request)."""
        self.on_cancel(_key(handle))

    def _end(self, key: Hashable, outcome: Outcome | None) -> None:
        with self._lock:
            goal = self._goals.get(key)
        if goal is not None:
            goal.outcome = outcome
            goal.ended.set()

    def goal_handle(self, key: Hashable) -> Any:
        """The rclpy handle of goal ``key`` while it waits for its end, else None."""
        with self._lock:
            goal = self._goals.get(key)
        return None if goal is None else goal.handle

    def settle(self) -> None:
        """The decisions and results of the last cycle to the waiting goals (a goal the follower refused after
        send_goal, e.g. one ending in the past, aborts with its code)."""
        out = self.output
        for key, rejection in out.decisions:
            if rejection is not None:
                self._end(key, Outcome(key, "aborted", rejection.code, rejection.error_string, self.follower.cycle))
        for key, outcome in out.results:
            self._end(key, outcome)

    def stop_goals(self) -> None:
        """End every goal still waiting (the station stops): they abort."""
        with self._lock:
            goals = list(self._goals.values())
        for g in goals:
            g.ended.set()

    def serve(self, call: ServiceCall) -> Any:
        """A ``controller_manager`` or dashboard call, answered by the control loop (None: it stopped)."""
        self.on_service(call)
        return call.wait()

    # ------------------------------------------------------------------------------------------------ set_io
    def serve_set_io(self, fun: int, pin: int, state: float, sleep: Callable[[float], None]) -> bool:
        """``set_io``: False for a request the driver refuses; else True once the output changed, polled every
        50 ms up to 10 times (False when it never did)."""
        write = self.set_io(fun, pin, state)
        if write is None:
            return False
        for _ in range(SET_IO_RETRIES + 1):
            if self.io.applied(write):
                return True
            sleep(SET_IO_POLL_S)
        return self.io.applied(write)

    # ------------------------------------------------------------------------------------------------ report
    def _report_transport(self) -> dict[str, Any]:
        opts = self.options
        return {"transport": {"middleware": "ros2 (rclpy)", "node": NODE_NAME, "distro": opts.distro,
                              "domain_id": self.domain_id, "network": opts.network,
                              "action": self.names.follow_joint_trajectory,
                              "rejected_at_send_goal": self.rejected_at_send_goal}}

    # --------------------------------------------------------------------------------------------------- run
    def run(self) -> dict[str, Any]:
        """Start rclpy and the node, run until SIGINT/SIGTERM or ``duration_s``; returns the final report."""
        from ur3hanoi.interface.ros2.ur_node import DriverNode

        if self.options.network == "loopback":
            os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        with self.signals(), self.rendering():
            node = DriverNode(self, self.options.distro, self.options.domain_id)
            try:
                self.domain_id = node.domain_id
                self.loop(self._ready_line(), lambda: None, node.publish)
            finally:
                self.stop_goals()
                node.close()
            self.close_sink()
            return self.write_report()

    def _ready_line(self) -> str:
        w, opts, st = self.world, self.options, self.station
        return (f"{READY_LINE} on ROS_DOMAIN_ID {self.domain_id} ({opts.network}): the UR driver's interface "
                f"({opts.distro}: {self.names.follow_joint_trajectory}), {st.name} ({st.robot.title}), {w.n_blocks} "
                f"blocks on tower {opts.start + 1}, {1.0 / w.config.period_s:g} Hz, speed scaling "
                f"{opts.speed_scaling:g}, {st.wiring.describe()} (pid {os.getpid()})")

