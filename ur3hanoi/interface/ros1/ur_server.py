"""``ur3hanoi ros-station --driver ur``: the official ROS 1 UR driver's interface (``ur_robot_driver``), served from
MuJoCo.

:class:`RosDriverServer` is the neutral :class:`~ur3hanoi.interface.urdriver.station.DriverStation` (the simulated
robot under the scaled joint trajectory controller, IO, records) on the ROS 1 station
(:class:`~ur3hanoi.interface.ros1.server.RosStation`: its master, guard, watch, spawn and remove topics). Names, types
and order are the driver's (:data:`ur3hanoi.interface.urdriver.facts.ROS1`):

- ``/joint_states`` (``sensor_msgs/JointState``, alphabetical joint order, position, velocity, effort) every cycle;
- ``/scaled_pos_joint_traj_controller/follow_joint_trajectory`` (``control_msgs/FollowJointTrajectoryAction``) with
  Debian's ``actionlib.ActionServer``: goals accepted or rejected with the controller's code and text, feedback every
  cycle, results; a new goal preempts, a cancel stops the arm on its ramp and holds;
- ``/ur_hardware_interface/set_io`` (``ur_msgs/SetIO``): answers as soon as the write is queued; served to clients of
  both ``ur_msgs`` texts (current Noetic's with ``PIN_*`` and 1.3.x's without: the same request and response bytes,
  see :class:`EitherSetIoSum`) and to ``md5sum *``;
- ``/ur_hardware_interface/io_states`` (``ur_msgs/IOStates``) and ``/speed_scaling_factor`` (``std_msgs/Float64``, a
  fraction) every cycle;
- ``/ur_hardware_interface/robot_program_running`` (``std_msgs/Bool``, latched);
- fault injection: ``/ur3hanoi/hold_arm`` (``std_msgs/Float64``: seconds the arm is held where it is) and
  ``/ur3hanoi/program_running`` (``std_msgs/Bool``: false stops the robot program, as on the pendant: the running
  goal is preempted (``JointTrajectoryController::stopping``), new goals are rejected with INVALID_GOAL and no
  ``error_string`` (``goalCB``, ros_controllers noetic-devel ``joint_trajectory_controller_impl.h``) until it runs
  again); the same at the times of ``--program-stop-at`` / ``--program-resume-at``;
- ``/controller_manager/list_controllers``, ``load_controller`` and ``switch_controller``
  (``controller_manager_msgs``, :class:`~ur3hanoi.interface.urdriver.controllers.Ros1ControllerManager`) and the
  dashboard's ``/ur_hardware_interface/dashboard/play``, ``stop`` (``std_srvs/Trigger``) and ``program_running``
  (``ur_dashboard_msgs/IsProgramRunning``), tied to the program state: UR's ``scripts/test_move`` runs against it
  unmodified (with :func:`~ur3hanoi.interface.ros1.ur_packages.write_ur_packages`' packages on its path).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ur3hanoi.interface.ros1.driver_msgs import OFFICIAL_MD5, DriverMessages, load_driver_messages
from ur3hanoi.interface.ros1.server import RosServerOptions, RosStation
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ROS1, ROS1_JOINT_STATE_ORDER
from ur3hanoi.interface.urdriver.follower import Feedback, Outcome
from ur3hanoi.interface.urdriver.goal import JointTolerance, Rejection, TrajectoryGoal, TrajectoryPoint
from ur3hanoi.interface.urdriver.io import IoStatesMessage
from ur3hanoi.interface.urdriver.services import ServiceCall
from ur3hanoi.interface.urdriver.station import DriverStation, DriverStationOptions

HOLD_TOPIC = "/ur3hanoi/hold_arm"
"""Fault injection: ``std_msgs/Float64`` seconds the arm is held (a person or an obstacle in the way)."""
PROGRAM_TOPIC = "/ur3hanoi/program_running"
"""Fault injection: ``std_msgs/Bool`` false = the robot program stopped on the pendant (the controller stops)."""
DASHBOARD = "/ur_hardware_interface/dashboard"
"""The ROS 1 driver's dashboard services (``ur_robot_driver``'s ``dashboard_client``, in the hardware interface's
namespace)."""
PROGRAM_RUNNING = ROS1.program_running
"""The driver's latched ``std_msgs/Bool``: whether the robot program runs."""


class EitherSetIoSum(str):
    """The ``ur_msgs/SetIO`` md5sum the station advertises (current Noetic's), equal also to ur_msgs 1.3.x's.

    The two texts differ only by the 20 ``PIN_*`` constants, which change the sum but not one byte on the wire;
    rospy's service server compares a client's sum with ``!=`` against the service class's, so this value lets it
    serve clients generated from either text (``md5sum *`` is accepted anyway).
    """

    ACCEPTED = (OFFICIAL_MD5["ur_msgs/SetIO"], OFFICIAL_MD5["ur_msgs/SetIO@1.3"])

    def __eq__(self, other: object) -> bool:
        return other in self.ACCEPTED or str.__eq__(self, other)

    def __ne__(self, other: object) -> bool:
        return not self.__eq__(other)

    __hash__ = str.__hash__


@dataclass(frozen=True)
class RosDriverOptions(RosServerOptions, DriverStationOptions):
    """What ``ros-station --driver ur`` runs: :class:`~ur3hanoi.interface.ros1.server.RosServerOptions` and
    :class:`~ur3hanoi.interface.urdriver.station.DriverStationOptions`."""


def goal_from_msg(msg: Any, now: Any) -> TrajectoryGoal:
    """A ``FollowJointTrajectoryGoal`` message as the neutral goal (``now``: the node's ``rospy.Time``)."""
    tr = msg.trajectory

    def tolerances(items: Any) -> tuple[JointTolerance, ...]:
        return tuple(JointTolerance(t.name, t.position, t.velocity, t.acceleration) for t in items)

    points = tuple(TrajectoryPoint(tuple(p.positions), tuple(p.velocities), tuple(p.accelerations), tuple(p.effort),
                                   p.time_from_start.to_sec()) for p in tr.points)
    stamp = tr.header.stamp
    start = None if stamp.is_zero() else (stamp - now).to_sec()
    return TrajectoryGoal(tuple(tr.joint_names), points, tolerances(msg.path_tolerance), tolerances(msg.goal_tolerance),
                          msg.goal_time_tolerance.to_sec(), start)


class RosDriverServer(RosStation, DriverStation):
    """The ``ros-station --driver ur`` node (see the module docstring). :meth:`run` blocks until stopped."""

    options: RosDriverOptions

    TOPIC_LOG: ClassVar[dict[str, str]] = {"goal": "follow_joint_trajectory", "cancel": "follow_joint_trajectory",
                                           "hold": HOLD_TOPIC.lstrip("/"), "io": "ur_hardware_interface/set_io",
                                           "spawn": "ur3hanoi/spawn", "remove": "ur3hanoi/remove_block",
                                           "program": PROGRAM_TOPIC.lstrip("/")}

    def __init__(self, options: RosDriverOptions, out: Callable[[str], None] | None = None,
                 report_out: Callable[[str], None] | None = None) -> None:
        super().__init__(options, out, report_out)
        self._handles: dict[str, Any] = {}  # goal id -> actionlib ServerGoalHandle, until its result is sent
        self._msgs: DriverMessages | None = None

    # ---------------------------------------------------------------------------------------------- callbacks
    def _on_goal_msg(self, gh: Any) -> None:
        key = gh.get_goal_id().id
        self._handles[key] = gh
        self.on_goal(key, goal_from_msg(gh.get_goal(), self._rospy.Time.now()))

    def _on_cancel_msg(self, gh: Any) -> None:
        self.on_cancel(gh.get_goal_id().id)

    def _on_set_io(self, req: Any) -> Any:
        assert self._msgs is not None
        return self._msgs.SetIO._response_class(success=self.set_io(req.fun, req.pin, req.state) is not None)

    # ------------------------------------------------------------------------------------------------ topics
    def _ready_detail(self) -> str:
        opts = self.options
        return (f"the UR driver's interface ({opts.profile.name}) at {1.0 / self.world.config.period_s:g} Hz, speed "
                f"slider {100 * opts.speed_scaling:g} %, {self.station.wiring.describe()}")

    def _open(self, rospy: Any) -> Callable[[], None]:
        import importlib

        actionlib = importlib.import_module("actionlib")
        sensor_msgs = importlib.import_module("sensor_msgs.msg")
        std_msgs = importlib.import_module("std_msgs.msg")
        m = self._msgs = load_driver_messages()
        set_io = type("SetIO", (), {"_type": m.SetIO._type, "_md5sum": EitherSetIoSum(m.SetIO._md5sum),
                                    "_request_class": m.SetIO._request_class,
                                    "_response_class": m.SetIO._response_class})
        pubs = (rospy.Publisher(ROS1.joint_states, sensor_msgs.JointState, queue_size=10),
                rospy.Publisher(ROS1.io_states, m.IOStates, queue_size=10),
                rospy.Publisher(ROS1.speed_scaling, std_msgs.Float64, queue_size=10))
        server = actionlib.ActionServer(ROS1.follow_joint_trajectory, m.FollowJointTrajectoryAction,
                                        self._on_goal_msg, self._on_cancel_msg, auto_start=False)
        server.start()
        rospy.Service(ROS1.set_io, set_io, self._on_set_io)
        rospy.Subscriber(HOLD_TOPIC, std_msgs.Float64, lambda msg: self.on_hold(msg.data), queue_size=10)
        rospy.Subscriber(PROGRAM_TOPIC, std_msgs.Bool, lambda msg: self.on_program(msg.data), queue_size=10)
        self._services(rospy)
        program = rospy.Publisher(PROGRAM_RUNNING, std_msgs.Bool, queue_size=1, latch=True)
        running = [self.output.program_running]
        program.publish(std_msgs.Bool(running[0]))
        order = np.array([CONTROLLER_JOINTS.index(n) for n in ROS1_JOINT_STATE_ORDER])
        unit = self.options.profile.speed_scaling_unit
        io_msg = IoStatesMessage(m)

        def publish() -> None:
            out = self.output
            js = sensor_msgs.JointState(name=list(ROS1_JOINT_STATE_ORDER), position=out.q[order].tolist(),
                                        velocity=out.qd[order].tolist(), effort=out.effort[order].tolist())
            js.header.stamp = rospy.Time.now()
            pubs[0].publish(js)
            pubs[1].publish(io_msg.update(out.io))
            pubs[2].publish(std_msgs.Float64(out.speed_scaling * unit))
            if out.program_running != running[0]:
                running[0] = out.program_running
                program.publish(std_msgs.Bool(running[0]))
            self._goal_events(m, out.decisions, out.feedback, out.results, rospy.Time.now())

        return publish

    def _services(self, rospy: Any) -> None:
        """``controller_manager``'s list, load and switch, the dashboard's play, stop and program_running
        (:mod:`~ur3hanoi.interface.urdriver.services`), with classes generated from the official texts."""
        from ur3hanoi.interface.ros1.ur_packages import service_classes

        c = service_classes()
        cm = "controller_manager_msgs/"

        def answer(call: ServiceCall) -> Any:
            self.on_service(call)
            return call.wait()

        def listing(_req: Any) -> Any:
            rows = answer(ServiceCall("list")) or []
            res = c[f"{cm}HardwareInterfaceResources"]
            states = [c[f"{cm}ControllerState"](name=n, state=s, type=t, claimed_resources=[] if not joints else [
                res(hardware_interface=f"hardware_interface::{t.split('_')[0].capitalize()}JointInterface",
                    resources=list(joints))]) for n, s, t, joints in rows]
            return c[f"{cm}ListControllers"]._response_class(controller=states)

        def switch(req: Any) -> Any:
            ok = answer(ServiceCall("switch", req.start_controllers, req.stop_controllers, req.strictness))
            return c[f"{cm}SwitchController"]._response_class(ok=bool(ok and ok[0]))

        def load(req: Any) -> Any:
            return c[f"{cm}LoadController"]._response_class(ok=bool(answer(ServiceCall("load", [req.name]))))

        def trigger(kind: str) -> Any:
            def call(_req: Any) -> Any:
                result = answer(ServiceCall(kind)) or (False, "the station stopped")
                return c["std_srvs/Trigger"]._response_class(success=result[0], message=result[1])
            return call

        def running(_req: Any) -> Any:
            ok, text, value = answer(ServiceCall("running")) or (False, "the station stopped", False)
            return c["ur_dashboard_msgs/IsProgramRunning"]._response_class(answer=text, program_running=value,
                                                                            success=ok)

        for name, srv, callback in (("list_controllers", "ListControllers", listing),
                                    ("switch_controller", "SwitchController", switch),
                                    ("load_controller", "LoadController", load)):
            rospy.Service(f"/controller_manager/{name}", c[cm + srv], callback)
        for kind, srv, callback in (("play", "std_srvs/Trigger", trigger("play")),
                                    ("stop", "std_srvs/Trigger", trigger("stop")),
                                    ("program_running", "ur_dashboard_msgs/IsProgramRunning", running)):
            rospy.Service(f"{DASHBOARD}/{kind}", c[srv], callback)

    def _goal_events(self, m: DriverMessages, decisions: tuple[tuple[Any, Rejection | None], ...],
                     feedback: tuple[Any, Feedback] | None, results: tuple[tuple[Any, Outcome], ...],
                     stamp: Any) -> None:
        """Hand the cycle's decisions, feedback and results to actionlib's goal handles."""
        for key, rejection in decisions:
            gh = self._handles.get(key)
            if gh is None:
                continue
            if rejection is None:
                gh.set_accepted()
            else:
                del self._handles[key]
                gh.set_rejected(m.FollowJointTrajectoryResult(error_code=int(rejection.code),
                                                              error_string=rejection.error_string))
        if feedback is not None and feedback[0] in self._handles:
            f = feedback[1]
            msg = m.FollowJointTrajectoryFeedback(joint_names=list(CONTROLLER_JOINTS))
            msg.header.stamp = stamp
            assert f.desired.qd is not None and f.desired.qdd is not None
            msg.desired = m.JointTrajectoryPoint(positions=f.desired.q.tolist(), velocities=f.desired.qd.tolist(),
                                                 accelerations=f.desired.qdd.tolist())
            msg.actual = m.JointTrajectoryPoint(positions=f.actual_q.tolist(), velocities=f.actual_qd.tolist())
            msg.error = m.JointTrajectoryPoint(positions=f.error_q.tolist(), velocities=f.error_qd.tolist())
            self._handles[feedback[0]].publish_feedback(msg)
        for key, o in results:
            gh = self._handles.pop(key, None)
            if gh is None:
                continue
            result = m.FollowJointTrajectoryResult(error_code=int(o.code), error_string=o.error_string)
            if o.status == "succeeded":
                gh.set_succeeded(result)
            elif o.status == "aborted":
                gh.set_aborted(result)
            else:  # canceled or preempted: the controller's setCanceled(), without a result
                gh.set_canceled()
