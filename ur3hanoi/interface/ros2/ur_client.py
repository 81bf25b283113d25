"""``ur3hanoi ros2-solve --driver ur``: the client's connection to the official UR ROS 2 driver, on rclpy.

:class:`RclpyDriverTransport` is the ROS 2 :class:`~ur3hanoi.interface.urdriver.client.DriverTransport`; the solve
itself (the plan as goals, suction checks, halts, timeouts, errors) is the middleware-neutral
:func:`~ur3hanoi.interface.urdriver.solve.run_driver_solve`. What is ROS 2's here:

- ``/joint_states`` is read **by joint name** (the driver guarantees no order);
- ``/speed_scaling_state_broadcaster/speed_scaling`` is in percent: divided by 100;
- a goal the controller refuses comes back ``accepted = false``, without a code or a reason (the driver logs it): the
  handle reports ``rejected`` and the solve ends with one line (exit 2);
- the driver sets no goal timeout (``goal_time`` 0): the neutral solve keeps its own and cancels;
- ``set_io`` blocks until the driver confirmed the output (up to about 0.5 s); the call here waits at most
  :data:`SET_IO_TIMEOUT_S`.

rclpy runs in a private context with an executor thread of its own; :meth:`RclpyDriverTransport.close` ends both on
every path. Loopback only (``ROS_AUTOMATIC_DISCOVERY_RANGE`` LOCALHOST) unless ``network="lab"``.
"""

from __future__ import annotations

import os
import threading
import time
from typing import Any

from ur3hanoi.errors import DriverError, InputError
from ur3hanoi.interface.ros2.distros import ROS_DISTROS
from ur3hanoi.interface.ros2.rclpy_env import import_interfaces, import_rclpy
from ur3hanoi.interface.ros2.ur_driver import goal_to_msg, io_from_msg, joint_positions, names_for
from ur3hanoi.interface.urdriver.client import DriverState, GoalResult
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal
from ur3hanoi.interface.urdriver.joint_record import JointRecord

CONNECT_TIMEOUT_S = 10.0
"""How long :meth:`RclpyDriverTransport.connect` waits for the driver [s]."""
SET_IO_TIMEOUT_S = 2.0
"""Longest wait for a ``set_io`` answer [s] (the driver's own check takes up to about 0.5 s)."""
_STATUS = {4: "succeeded", 5: "canceled", 6: "aborted"}
"""``action_msgs/GoalStatus``: SUCCEEDED 4, CANCELED 5, ABORTED 6 (anything else ends as ``lost``)."""


GOAL_RESPONSE_WAIT_S = 1.0
"""[s] how long the executor thread waits for :meth:`RclpyDriverTransport.send_goal` to register a goal request whose
answer already arrived (see :func:`_race_free`)."""


def _race_free(action_client: Any) -> Any:
    """``rclpy.action.ActionClient`` without the race of a goal sent from another thread than the executor's
    (ros2/rclpy#1123, unfixed in Jazzy's rclpy): ``send_goal_async`` registers the request's sequence number only after
    sending it, and a driver answering before that makes the executor drop the answer ("Ignoring unexpected goal
    response"): the goal's future never completes and the solve times out. Here the executor thread waits for the
    registration first (it follows within microseconds; at most :data:`GOAL_RESPONSE_WAIT_S`)."""

    class RaceFreeActionClient(action_client):
        async def execute(self, taken_data: Any) -> Any:
            if "goal" in taken_data:
                sequence = taken_data["goal"][0]
                end = time.monotonic() + GOAL_RESPONSE_WAIT_S
                while sequence not in self._goal_sequence_number_to_goal_id and time.monotonic() < end:
                    time.sleep(0.0005)
            return await super().execute(taken_data)

    return RaceFreeActionClient


class RclpyGoal:
    """A goal sent through :class:`RclpyDriverTransport` (a
    :class:`~ur3hanoi.interface.urdriver.client.GoalHandle`)."""

    def __init__(self, sent: Any, wake: threading.Event) -> None:
        self._sent, self._wake = sent, wake
        self._handle: Any = None
        self._result: Any = None
        self._cancel = False
        sent.add_done_callback(self._on_sent)

    def _on_sent(self, future: Any) -> None:
        handle = future.result()
        self._handle = handle
        if handle is not None and handle.accepted:
            self._result = handle.get_result_async()
            self._result.add_done_callback(lambda _: self._wake.set())
            if self._cancel:
                handle.cancel_goal_async()
        self._wake.set()

    def done(self) -> bool:
        if self._handle is None:
            return self._sent.done() and self._sent.result() is None
        return not self._handle.accepted or (self._result is not None and self._result.done())

    def result(self) -> GoalResult:
        if self._handle is None or not self._handle.accepted:
            return GoalResult("rejected", None, "")
        response = self._result.result()
        status = _STATUS.get(int(response.status), "lost")
        code = None if status == "canceled" else int(response.result.error_code)
        return GoalResult(status, code, str(response.result.error_string))  # type: ignore[arg-type]

    def cancel(self) -> None:
        self._cancel = True
        if self._handle is not None and self._handle.accepted:
            self._handle.cancel_goal_async()


class RclpyDriverTransport:
    """The UR ROS 2 driver's interface through rclpy (see the module docstring).

    Args:
        distro: the robot's ROS 2 distribution (names, FollowJointTrajectory layout).
        domain_id: ROS_DOMAIN_ID (None: ``$ROS_DOMAIN_ID``, else 0).
        network: ``loopback`` or ``lab``.
        connect_timeout_s: how long :meth:`connect` waits for the driver.
    """

    def __init__(self, distro: str, domain_id: int | None = None, network: str = "loopback",
                 connect_timeout_s: float = CONNECT_TIMEOUT_S) -> None:
        if distro not in ROS_DISTROS:
            raise InputError(f"ROS 2 distribution {distro!r} is invalid: expected one of {', '.join(ROS_DISTROS)}")
        if network not in ("loopback", "lab"):
            raise InputError(f"network {network!r} is invalid with the UR driver's interface (rclpy): expected "
                             "loopback or lab")
        self.distro, self.domain_id, self.network = distro, domain_id, network
        self.connect_timeout_s = connect_timeout_s
        self.names = names_for(distro)
        self.where = f"ROS_DOMAIN_ID {'$ROS_DOMAIN_ID' if domain_id is None else domain_id} ({network}, {distro})"
        self._wake = threading.Event()
        self._lock = threading.Lock()
        self._state = DriverState()
        self._started = False
        self.record = JointRecord()

    def now(self) -> float:
        return time.monotonic()

    # ------------------------------------------------------------------------------------------------ connect
    def _start(self) -> None:
        from ur3hanoi.interface.ros2.ur_node import check_layout

        rclpy = import_rclpy()
        action, ur_srv, ur_msg, sensor_msgs, std_msgs, self._traj = import_interfaces(
            "control_msgs.action", "ur_msgs.srv", "ur_msgs.msg", "sensor_msgs.msg", "std_msgs.msg",
            "trajectory_msgs.msg")
        from rclpy.action import ActionClient
        from rclpy.executors import SingleThreadedExecutor

        check_layout(action, self.distro)
        if self.network == "loopback":
            os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
        self._rclpy, self._action = rclpy, action
        self.context = rclpy.Context()
        from rclpy.signals import SignalHandlerOptions

        # ur3hanoi's own handlers turn SIGINT/SIGTERM into its clean-up (the running goal canceled).
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO,
                   **({} if self.domain_id is None else {"domain_id": self.domain_id}))
        self._started = True
        self.where = f"ROS_DOMAIN_ID {self.context.get_domain_id()} ({self.network}, {self.distro})"
        node = self.node = rclpy.create_node("ur3hanoi_solve", context=self.context)
        n = self.names
        node.create_subscription(sensor_msgs.JointState, n.joint_states, self._on_joints, 10)
        node.create_subscription(ur_msg.IOStates, n.io_states, self._on_io, 10)
        node.create_subscription(std_msgs.Float64, n.speed_scaling, self._on_scaling, 10)
        from rclpy.qos import DurabilityPolicy, QoSProfile

        # Transient local as the driver publishes it: the state before this client connected arrives too.
        node.create_subscription(std_msgs.Bool, n.program_running, self._on_program,
                                 QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self.client = _race_free(ActionClient)(node, action.FollowJointTrajectory, n.follow_joint_trajectory)
        self.set_io_client = node.create_client(ur_srv.SetIO, n.set_io)
        self._set_io_type = ur_srv.SetIO
        # One thread: no callback here blocks, and the multi-threaded executor's hand-off to a pool cost the io_states
        # at 500 Hz: a dropped block reached the cancel 15-30 control cycles late, now 1-2 (bench/bench_driver.py).
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(node)
        self.thread = threading.Thread(target=self.executor.spin, name="rclpy-executor", daemon=True)
        self.thread.start()

    def _missing(self) -> list[str]:
        s, n = self._state, self.names
        return [what for what, ok in ((n.joint_states, s.q is not None), (n.io_states, s.io is not None),
                                      (f"the action server {n.follow_joint_trajectory}", self.client.server_is_ready()),
                                      (f"the service {n.set_io}", self.set_io_client.service_is_ready())) if not ok]

    def connect(self) -> None:
        """Wait (``connect_timeout_s``) for joint states, ``io_states``, the action server and ``set_io``.

        Raises:
            DriverError: one line naming what did not appear.
        """
        if not self._started:
            self._start()
        deadline = time.monotonic() + self.connect_timeout_s
        while self._missing() and time.monotonic() < deadline:
            time.sleep(0.05)
        missing = self._missing()
        if missing:
            raise DriverError(f"no UR driver on {self.where} within {self.connect_timeout_s:g} s: missing "
                              f"{', '.join(missing)} (is the driver running, on this ROS_DOMAIN_ID and network, "
                              f"with --ros-distro {self.distro}'s names?)")

    # ----------------------------------------------------------------------------------------------- topics
    def _on_joints(self, msg: Any) -> None:
        q = joint_positions(msg.name, msg.position)
        if q is not None:
            now = time.monotonic()
            self.record.add(now, q)
            with self._lock:
                s = self._state
                self._state = DriverState(q, now, s.io, s.speed_scaling, s.program_running)
            self._wake.set()

    def _on_io(self, msg: Any) -> None:
        io = io_from_msg(msg)
        with self._lock:
            s = self._state
            self._state = DriverState(s.q, s.t_q, io, s.speed_scaling, s.program_running)
        self._wake.set()

    def _on_scaling(self, msg: Any) -> None:
        with self._lock:
            s = self._state
            self._state = DriverState(s.q, s.t_q, s.io, float(msg.data) / 100.0,  # the ROS 2 driver's percent
                                      s.program_running)

    def _on_program(self, msg: Any) -> None:
        with self._lock:
            s = self._state
            self._state = DriverState(s.q, s.t_q, s.io, s.speed_scaling, bool(msg.data))
        self._wake.set()

    def latest(self) -> DriverState:
        with self._lock:
            return self._state

    # -------------------------------------------------------------------------------------------- commands
    def send_goal(self, goal: TrajectoryGoal) -> RclpyGoal:
        msg = goal_to_msg(goal, self._action.FollowJointTrajectory, self._traj)
        return RclpyGoal(self.client.send_goal_async(msg), self._wake)

    def set_io(self, fun: int, pin: int, state: float) -> bool:
        request = self._set_io_type.Request(fun=fun, pin=pin, state=float(state))
        future = self.set_io_client.call_async(request)
        done = threading.Event()
        future.add_done_callback(lambda _: done.set())
        if not done.wait(SET_IO_TIMEOUT_S):
            future.cancel()
            return False
        response = future.result()
        return bool(response is not None and response.success)

    def wait(self, timeout_s: float) -> None:
        self._wake.wait(timeout_s)
        self._wake.clear()

    def close(self) -> None:
        """Stop the executor, destroy the node, shut rclpy's context down (idempotent)."""
        if not self._started:
            return
        self._started = False
        try:
            self.executor.shutdown(timeout_sec=2.0)
            self.thread.join(timeout=2.0)
            self.node.destroy_node()
        finally:
            self._rclpy.try_shutdown(context=self.context)
