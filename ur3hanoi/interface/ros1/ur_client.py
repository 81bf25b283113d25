"""``ur3hanoi ros-solve --driver ur``: a rospy client of the official ROS 1 UR driver (or ``ros-station --driver ur``).

:class:`RosDriverTransport` is the ROS 1 :class:`~ur3hanoi.interface.urdriver.client.DriverTransport`: it reads
``/joint_states`` by joint name (the driver lists them alphabetically), ``/ur_hardware_interface/io_states`` and
``/speed_scaling_factor``; it sends goals to ``/scaled_pos_joint_traj_controller/follow_joint_trajectory`` with
Debian's ``actionlib.SimpleActionClient`` and calls ``/ur_hardware_interface/set_io`` with the ``md5sum *`` header,
which both ``ur_msgs`` versions' servers accept. Every callback wakes :meth:`~RosDriverTransport.wait`, so the solve
reacts to an ``io_states`` without the block within the message's arrival, not a poll period later. The master is
watched as by :class:`ur3hanoi.interface.ros1.client.RosArm`.
"""

from __future__ import annotations

import importlib
import os
import sys
import threading
import time
from typing import Any

import numpy as np

from ur3hanoi.interface.ros1.errors import RosError
from ur3hanoi.interface.urdriver.client import DriverState, GoalResult
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS, ROS1
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal
from ur3hanoi.interface.urdriver.io import IoStates
from ur3hanoi.interface.urdriver.joint_record import JointRecord

# actionlib_msgs/GoalStatus values (SimpleActionClient.get_state) and how the solve reads them.
_STATUS = {3: "succeeded", 4: "aborted", 5: "rejected", 2: "preempted", 8: "canceled", 9: "lost"}


class RosGoal:
    """A goal sent with :class:`RosDriverTransport` (a :class:`~ur3hanoi.interface.urdriver.client.GoalHandle`)."""

    def __init__(self, client: Any, wake: threading.Condition) -> None:
        self.client, self._wake = client, wake
        self._done: tuple[int, Any] | None = None

    def done_cb(self, state: int, result: Any) -> None:
        with self._wake:
            self._done = (state, result)
            self._wake.notify_all()

    def done(self) -> bool:
        return self._done is not None

    def result(self) -> GoalResult:
        assert self._done is not None, "result() before done()"
        state, result = self._done
        status = _STATUS.get(state, "lost")
        if result is None or status in ("preempted", "canceled", "lost"):
            return GoalResult(status)  # type: ignore[arg-type]
        return GoalResult(status, int(result.error_code), str(result.error_string))  # type: ignore[arg-type]

    def cancel(self) -> None:
        self.client.cancel_goal()


class RosDriverTransport:
    """The ROS 1 UR driver seen from a client (see the module docstring). Call :meth:`connect` first.

    Args:
        master_uri: ROS master (None: ``ROS_MASTER_URI``, else http://localhost:11311).
        connect_timeout_s: how long :meth:`connect` waits for the driver.
    """

    def __init__(self, master_uri: str | None = None, connect_timeout_s: float = 15.0) -> None:
        from ur3hanoi.interface.ros1.master import master_uri_from_env

        self.master_uri = self.where = master_uri or master_uri_from_env()
        self.connect_timeout_s = connect_timeout_s
        self._wake = threading.Condition()
        self._state = DriverState()
        self._rospy: Any = None
        self._client: Any = None
        self._set_io: Any = None
        self._msgs: Any = None
        self._watch: Any = None
        self.names_seen: tuple[str, ...] = ()
        self.record = JointRecord()

    # --------------------------------------------------------------------------------------------- callbacks
    def _update(self, **fields: Any) -> None:
        with self._wake:
            s = self._state
            self._state = DriverState(**{"q": s.q, "t_q": s.t_q, "io": s.io, "speed_scaling": s.speed_scaling,
                                         "program_running": s.program_running, **fields})
            self._wake.notify_all()

    def _on_joint_states(self, msg: Any) -> None:
        index = {n: i for i, n in enumerate(msg.name)}
        self.names_seen = tuple(msg.name)
        if all(j in index for j in CONTROLLER_JOINTS) and len(msg.position) == len(msg.name):
            q = np.array([msg.position[index[j]] for j in CONTROLLER_JOINTS], dtype=float)
            if np.all(np.isfinite(q)):
                now = time.monotonic()
                self.record.add(now, q)
                self._update(q=q, t_q=now)

    def _on_io_states(self, msg: Any) -> None:
        io = IoStates(tuple(bool(d.state) for d in msg.digital_in_states),
                      tuple(bool(d.state) for d in msg.digital_out_states),
                      tuple((int(a.domain), float(a.state)) for a in msg.analog_in_states),
                      tuple((int(a.domain), float(a.state)) for a in msg.analog_out_states))
        self._update(io=io)

    def _on_speed_scaling(self, msg: Any) -> None:
        self._update(speed_scaling=float(msg.data))

    # --------------------------------------------------------------------------------------------- connection
    def connect(self) -> None:
        """Register with the master and wait for the driver's topics, action server and ``set_io``.

        Raises:
            RosError: no master, or the driver's interface is not all there within ``connect_timeout_s``.
        """
        from ur3hanoi.interface.ros1.driver_msgs import load_driver_messages
        from ur3hanoi.interface.ros1.env import import_rospy
        from ur3hanoi.interface.ros1.master import MasterUri, master_pid
        from ur3hanoi.interface.ros1.watch import MasterWatch, quick_shutdown

        MasterUri.parse(self.master_uri)
        pid = master_pid(self.master_uri, timeout=2.0)
        if pid is None:
            raise RosError(f"no ROS master answers at {self.master_uri}: start the UR driver (ur_robot_driver) or "
                           "`ur3hanoi ros-station --driver ur`, or set ROS_MASTER_URI")
        m = self._msgs = load_driver_messages()
        rospy = self._rospy = import_rospy()
        actionlib = importlib.import_module("actionlib")
        sensor_msgs = importlib.import_module("sensor_msgs.msg")
        std_msgs = importlib.import_module("std_msgs.msg")
        os.environ["ROS_MASTER_URI"] = self.master_uri
        rospy.init_node("ur3hanoi_solve", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
        quick_shutdown()
        self._watch = MasterWatch(self.master_uri, pid).start()
        rospy.Subscriber(ROS1.joint_states, sensor_msgs.JointState, self._on_joint_states, tcp_nodelay=True)
        rospy.Subscriber(ROS1.io_states, m.IOStates, self._on_io_states, tcp_nodelay=True)
        rospy.Subscriber(ROS1.speed_scaling, std_msgs.Float64, self._on_speed_scaling, tcp_nodelay=True)
        rospy.Subscriber(ROS1.program_running, std_msgs.Bool, lambda msg: self._update(program_running=bool(msg.data)),
                         tcp_nodelay=True)
        self._client = actionlib.SimpleActionClient(ROS1.follow_joint_trajectory, m.FollowJointTrajectoryAction)
        self._set_io = rospy.ServiceProxy(ROS1.set_io, m.SetIO, headers={"md5sum": "*"})
        deadline = time.monotonic() + self.connect_timeout_s
        server = self._client.wait_for_server(rospy.Duration(self.connect_timeout_s))
        service = True
        try:
            self._set_io.wait_for_service(max(0.1, deadline - time.monotonic()))
        except rospy.ROSException:
            service = False
        with self._wake:
            self._wake.wait_for(lambda: self._state.q is not None and self._state.io is not None,
                                max(0.0, deadline - time.monotonic()))
        missing = [name for name, ok in ((ROS1.joint_states, self._state.q is not None),
                                         (ROS1.io_states, self._state.io is not None),
                                         (f"the action server {ROS1.follow_joint_trajectory}", server),
                                         (f"the service {ROS1.set_io}", service)) if not ok]
        if missing:
            seen = f" (joint states name {', '.join(self.names_seen)})" if self.names_seen and self._state.q is None \
                else ""
            raise RosError(f"no {', '.join(missing)} within {self.connect_timeout_s:g} s on {self.master_uri}{seen}: "
                           "is the UR driver (ur_robot_driver, or `ur3hanoi ros-station --driver ur`) running?")

    def close(self) -> None:
        """Stop watching the master and unregister the node (not with a master that is gone)."""
        from ur3hanoi.interface.ros1.watch import end_client

        watch, self._watch = self._watch, None
        end_client(watch, self._rospy)

    def _check_master(self) -> None:
        from ur3hanoi.interface.ros1.watch import raise_if_lost

        raise_if_lost(self._watch, self.master_uri, "the driver")

    # ---------------------------------------------------------------------------------------------- transport
    def now(self) -> float:
        return time.monotonic()

    def latest(self) -> DriverState:
        self._check_master()
        return self._state

    def send_goal(self, goal: TrajectoryGoal) -> RosGoal:
        m = self._msgs
        msg = m.FollowJointTrajectoryGoal()
        msg.trajectory.joint_names = list(goal.joint_names)
        msg.trajectory.points = [m.JointTrajectoryPoint(positions=list(p.positions), velocities=list(p.velocities),
                                                        accelerations=list(p.accelerations),
                                                        time_from_start=self._rospy.Duration.from_sec(
                                                            p.time_from_start_s))
                                 for p in goal.points]
        msg.goal_time_tolerance = self._rospy.Duration.from_sec(goal.goal_time_tolerance_s)
        handle = RosGoal(self._client, self._wake)
        self._client.send_goal(msg, done_cb=handle.done_cb)
        return handle

    def set_io(self, fun: int, pin: int, state: float) -> bool:
        try:
            return bool(self._set_io(fun, pin, state).success)
        except (self._rospy.ServiceException, self._rospy.ROSException) as exc:
            raise RosError(f"set_io(fun={fun}, pin={pin}, state={state:g}) failed on {self.master_uri}: "
                           f"{exc}") from None

    def wait(self, timeout_s: float) -> None:
        self._check_master()
        with self._wake:
            self._wake.wait(timeout_s)
