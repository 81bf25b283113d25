"""The rclpy node of ``ros2-station --driver ur`` (:class:`~ur3hanoi.interface.ros2.ur_station.Ros2DriverStation`):
its publishers, the ``follow_joint_trajectory`` action server, the ``set_io`` service and the fault topics, in a
private rclpy context whose executor spins in a thread pool of its own.

rclpy comes from :func:`~ur3hanoi.interface.ros2.rclpy_env.import_rclpy` (a sourced ROS 2 or ``ros2-env``); the
message packages must have the FollowJointTrajectory layout of the distribution served (Kilted and later add the
feedback's ``index``), else one line says which and how to get the other.
"""

from __future__ import annotations

import contextlib
import os
import threading
import time
from collections.abc import Callable
from typing import Any, Protocol

from ur3hanoi.interface.ros2.distros import ROS_DISTROS
from ur3hanoi.interface.ros2.errors import RclpyUnavailableError
from ur3hanoi.interface.ros2.rclpy_env import import_interfaces, import_rclpy
from ur3hanoi.interface.ros2.ur_driver import FEEDBACK_HZ, SPEED_SCALING_HZ, set_duration
from ur3hanoi.interface.urdriver.controllers import ControllerManager, Ros1ControllerManager
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ROS1_JOINT_STATE_ORDER, DriverNames
from ur3hanoi.interface.urdriver.io import IoStatesMessage
from ur3hanoi.interface.urdriver.services import ServiceCall, controller_rows
from ur3hanoi.interface.urdriver.station import CycleOutput, DriverStationOptions


class Served(Protocol):
    """What the node serves (:class:`~ur3hanoi.interface.ros2.ur_station.Ros2DriverStation`): the options, names and
    last cycle's output, and the callbacks the node's threads call."""

    @property
    def options(self) -> DriverStationOptions: ...
    @property
    def names(self) -> DriverNames: ...
    @property
    def output(self) -> CycleOutput: ...
    @property
    def controllers(self) -> ControllerManager | Ros1ControllerManager: ...
    def goal_callback(self, request: Any, now_s: float, controller: str) -> bool: ...
    def serve(self, call: ServiceCall) -> Any: ...
    def accepted(self, handle: Any, now_s: float) -> None: ...
    def execute(self, handle: Any, action: Any) -> Any: ...
    def cancel(self, handle: Any) -> None: ...
    def serve_set_io(self, fun: int, pin: int, state: float, sleep: Callable[[float], None]) -> bool: ...
    def goal_handle(self, key: Any) -> Any: ...
    def settle(self) -> None: ...
    def on_spawn(self, tower: Any) -> None: ...
    def on_remove(self, block: Any) -> None: ...
    def on_hold(self, seconds: float) -> None: ...
    def on_program(self, running: bool) -> None: ...


JOINT_STATE_ORDER = ROS1_JOINT_STATE_ORDER
"""The order of the published ``/joint_states``: none is guaranteed on ROS 2; this one breaks a client that indexes
by position, as a real robot may."""
_THREADS = 8
"""Executor threads: every running goal's execute callback and a ``set_io`` call wait in one."""
PUBLICATION_MODE = ("RMW_FASTRTPS_PUBLICATION_MODE", "ASYNCHRONOUS")
"""Fast DDS sends the station's samples from a thread of its own: publishing never waits for a client that reads or
acknowledges late (rclpy holds the GIL while a synchronous write waits: a slow reader of the 500 Hz joint states
stalled the control loop for milliseconds a cycle, bench/bench_driver.py), as the real driver's controllers never
wait for theirs (ros2_control publishes through realtime_tools' RealtimePublisher, from its own thread). The wire,
the QoS and the order per topic are the same; a value the user set is kept; other RMWs ignore it."""


def check_layout(action: Any, distro: str) -> None:
    """One line when the imported ``control_msgs`` does not have ``distro``'s FollowJointTrajectory layout."""
    has_index = "index" in action.FollowJointTrajectory.Feedback.get_fields_and_field_types()
    if has_index != (ROS_DISTROS[distro] == "kilted"):
        have = "Kilted and later (control_msgs >= 6.3)" if has_index else "Humble/Jazzy (control_msgs < 6.3)"
        raise RclpyUnavailableError(f"the imported control_msgs has the {have} FollowJointTrajectory, not "
                                    f"{distro}'s: use --ros-distro to match it, or eval \"$(ur3hanoi ros2-env "
                                    f"--distro {distro})\"")


class DriverNode:
    """The node (see the module docstring); :meth:`publish` once per control cycle, :meth:`close` at the end."""

    def __init__(self, station: Served, distro: str, domain_id: int | None) -> None:
        rclpy = import_rclpy()
        action, ur_srv, ur_msg, sensor_msgs, std_msgs = import_interfaces(
            "control_msgs.action", "ur_msgs.srv", "ur_msgs.msg", "sensor_msgs.msg", "std_msgs.msg")
        from rclpy.action import ActionServer, CancelResponse, GoalResponse
        from rclpy.callback_groups import ReentrantCallbackGroup
        from rclpy.executors import MultiThreadedExecutor

        check_layout(action, distro)
        self.station, self.rclpy, self.action, self.ur_msg = station, rclpy, action, ur_msg
        self.sensor_msgs, self.std_msgs = sensor_msgs, std_msgs
        os.environ.setdefault(*PUBLICATION_MODE)  # read when the context's participant is made
        self.context = rclpy.Context()
        kwargs = {} if domain_id is None else {"domain_id": domain_id}
        from rclpy.signals import SignalHandlerOptions

        # The station's own handlers stop the loop (SIGINT, SIGTERM) and write the report (SIGUSR1).
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO, **kwargs)
        try:
            self.domain_id = self.context.get_domain_id()
            self.node = node = rclpy.create_node("ur3hanoi_ur_driver", context=self.context)
            names, group = station.names, ReentrantCallbackGroup()
            self.clock = node.get_clock()
            self.pub_joints = node.create_publisher(sensor_msgs.JointState, names.joint_states, 10)
            self.pub_io = node.create_publisher(ur_msg.IOStates, names.io_states, 10)
            self.pub_scaling = node.create_publisher(std_msgs.Float64, names.speed_scaling, 10)
            # Latched as the GPIO controller's (gpio_controller.cpp @ a16a268 lines 249-266: SystemDefaultsQoS,
            # transient_local): a client that connects later still gets the program's state.
            from rclpy.qos import DurabilityPolicy, QoSProfile

            latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL)
            self.pub_program = node.create_publisher(std_msgs.Bool, names.program_running, latched)
            self._program: bool | None = None

            def goal_cb(request: Any, controller: str) -> Any:
                ok = station.goal_callback(request, self._now(), controller)
                return GoalResponse.ACCEPT if ok else GoalResponse.REJECT

            def accepted_cb(handle: Any) -> None:
                station.accepted(handle, self._now())
                handle.execute()

            def cancel_cb(handle: Any) -> Any:
                station.cancel(handle)
                return CancelResponse.ACCEPT

            fjt = action.FollowJointTrajectory
            assert isinstance(station.controllers, ControllerManager)  # the ROS 2 station's
            self.servers = [ActionServer(node, fjt, f"/{c.name}/follow_joint_trajectory",
                                         lambda h: station.execute(h, fjt),
                                         goal_callback=lambda r, name=c.name: goal_cb(r, name),
                                         handle_accepted_callback=accepted_cb, cancel_callback=cancel_cb,
                                         callback_group=group)
                            for c in station.controllers.controllers.values() if c.action]
            self._services(node, group)

            def set_io(request: Any, response: Any) -> Any:
                response.success = station.serve_set_io(int(request.fun), int(request.pin), float(request.state),
                                                        time.sleep)
                return response

            node.create_service(ur_srv.SetIO, names.set_io, set_io, callback_group=group)
            node.create_subscription(std_msgs.Int32, "ur3hanoi/spawn", lambda m: station.on_spawn(int(m.data)), 10)
            node.create_subscription(std_msgs.Int32, "ur3hanoi/remove_block",
                                     lambda m: station.on_remove(int(m.data)), 10)
            node.create_subscription(std_msgs.Float64, "ur3hanoi/hold_arm",
                                     lambda m: station.on_hold(float(m.data)), 10)
            node.create_subscription(std_msgs.Bool, "ur3hanoi/program_running",
                                     lambda m: station.on_program(bool(m.data)), 10)
            self.executor = MultiThreadedExecutor(num_threads=_THREADS, context=self.context)
            self.executor.add_node(node)
            self.thread = threading.Thread(target=self.executor.spin, name="rclpy-executor", daemon=True)
            self.thread.start()
        except BaseException:
            self.rclpy.try_shutdown(context=self.context)
            raise
        self._order = [CONTROLLER_JOINTS.index(j) for j in JOINT_STATE_ORDER]
        self._io = IoStatesMessage(ur_msg)
        self._js = sensor_msgs.JointState(name=list(JOINT_STATE_ORDER))
        self._next_scaling = self._next_feedback = 0.0

    def _services(self, node: Any, group: Any) -> None:
        """``controller_manager``'s list and switch, the dashboard's play, stop and program_running."""
        cm_srv, cm_msg, std_srvs, dash = import_interfaces("controller_manager_msgs.srv", "controller_manager_msgs.msg",
                                                           "std_srvs.srv", "ur_dashboard_msgs.srv")
        st = self.station

        def listing(_request: Any, response: Any) -> Any:
            rows = st.serve(ServiceCall("list")) or []
            response.controller = [cm_msg.ControllerState(**row) for row in controller_rows(rows)]
            return response

        def switch(request: Any, response: Any) -> Any:
            answer = st.serve(ServiceCall("switch", list(request.activate_controllers),
                                          list(request.deactivate_controllers), int(request.strictness)))
            response.ok, response.message = answer if answer is not None else (False, "the station stopped")
            return response

        def trigger(kind: str) -> Callable[[Any, Any], Any]:
            def call(_request: Any, response: Any) -> Any:
                answer = st.serve(ServiceCall(kind))
                response.success, response.message = answer if answer is not None else (False, "the station stopped")
                return response
            return call

        def running(_request: Any, response: Any) -> Any:
            answer = st.serve(ServiceCall("running"))
            if answer is not None:
                response.success, response.answer, response.program_running = answer
            return response

        for srv_type, name, callback in ((cm_srv.ListControllers, "/controller_manager/list_controllers", listing),
                                         (cm_srv.SwitchController, "/controller_manager/switch_controller", switch),
                                         (std_srvs.Trigger, "/dashboard_client/play", trigger("play")),
                                         (std_srvs.Trigger, "/dashboard_client/stop", trigger("stop")),
                                         (dash.IsProgramRunning, "/dashboard_client/program_running", running)):
            node.create_service(srv_type, name, callback, callback_group=group)

    def _now(self) -> float:
        return float(self.clock.now().nanoseconds) * 1e-9

    def publish(self) -> None:
        """One control cycle's messages: joint states and ``io_states`` every cycle, speed scaling at 100 Hz, the
        running goal's feedback at 20 Hz; then the goals decided or ended this cycle are settled."""
        st, out = self.station, self.station.output
        stamp = self.clock.now().to_msg()
        js = self._js
        js.header.stamp = stamp
        js.position = [float(out.q[i]) for i in self._order]
        js.velocity = [float(out.qd[i]) for i in self._order]
        js.effort = [float(out.effort[i]) for i in self._order]
        self.pub_joints.publish(js)
        self.pub_io.publish(self._io.update(out.io))
        if out.program_running != self._program:
            self._program = out.program_running
            self.pub_program.publish(self.std_msgs.Bool(data=out.program_running))
        now = time.monotonic()
        if now >= self._next_scaling:
            self._next_scaling = now + 1.0 / SPEED_SCALING_HZ
            self.pub_scaling.publish(self.std_msgs.Float64(data=out.speed_scaling * st.options.profile
                                                           .speed_scaling_unit))
        if out.feedback is not None and now >= self._next_feedback:
            self._next_feedback = now + 1.0 / FEEDBACK_HZ
            self._feedback(out.feedback, stamp)
        st.settle()

    def _feedback(self, feedback: Any, stamp: Any) -> None:
        key, fb = feedback
        handle = self.station.goal_handle(key)
        if handle is None:
            return
        msg = self.action.FollowJointTrajectory.Feedback()
        msg.header.stamp = stamp
        msg.joint_names = list(CONTROLLER_JOINTS)
        d = fb.desired
        msg.desired.positions = [float(x) for x in d.q]
        if d.qd is not None:
            msg.desired.velocities = [float(x) for x in d.qd]
        if d.qdd is not None:
            msg.desired.accelerations = [float(x) for x in d.qdd]
        msg.actual.positions, msg.actual.velocities = list(map(float, fb.actual_q)), list(map(float, fb.actual_qd))
        msg.error.positions, msg.error.velocities = list(map(float, fb.error_q)), list(map(float, fb.error_qd))
        for point in (msg.desired, msg.actual, msg.error):
            set_duration(point.time_from_start, 0.0)
        with contextlib.suppress(Exception):  # the goal ended meanwhile (rclpy refuses feedback of a terminal goal)
            handle.publish_feedback(msg)

    def close(self) -> None:
        """Stop the executor, destroy the node, shut the context down (every exit path)."""
        try:
            self.executor.shutdown(timeout_sec=2.0)
        finally:
            self.thread.join(timeout=2.0)
            self.node.destroy_node()
            self.rclpy.try_shutdown(context=self.context)

