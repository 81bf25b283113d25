"""A rospy client of the course's interface: ``ur3/command`` out, ``ur3/position`` and ``ur3/gripper_input`` in.

:class:`RosArm` is the transport-neutral :class:`ur3hanoi.interface.course.client.TopicArm` (moves, waits, suction
checks, timeouts) bound to rospy: it registers with the master and waits for the driver before the first command (a
rospy publisher drops messages until a subscriber is connected); the callbacks run in rospy's threads. The master is
watched (:class:`~ur3hanoi.interface.ros1.watch.MasterWatch`): once it is gone, the next wait raises :class:`RosError`
(one line, exit 2), as when the positions stop.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Callable
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.course.client import ArmConfig, TopicArm, Topics
from ur3hanoi.interface.ros1.errors import RosError

TOPICS = Topics(command="ur3/command", position="ur3/position", gripper="ur3/gripper_input")


class RosArm(TopicArm):
    """The robot as seen through the course's ROS topics (see the module docstring). Call :meth:`connect` first.

    Args:
        config: command speed, tolerances and timeouts.
        master_uri: ROS master (None: ``ROS_MASTER_URI``, else http://localhost:11311).
        log: where re-publish notices go.
    """

    def __init__(self, config: ArmConfig | None = None, master_uri: str | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.interface.ros1.master import master_uri_from_env

        super().__init__(config if config is not None else ArmConfig(), TOPICS, log)
        self.master_uri = master_uri or master_uri_from_env()
        self._rospy: Any = None
        self._msgs: Any = None
        self._pub: Any = None
        self._watch: Any = None  # the MasterWatch once connected

    # --------------------------------------------------------------------------------------------- callbacks
    def _on_position(self, msg: Any) -> None:
        self._position(np.array(msg.position, dtype=float))

    def _on_gripper(self, msg: Any) -> None:
        self._feedback(int(msg.DIGIN), float(msg.AIN0))

    # --------------------------------------------------------------------------------------------- connection
    def connect(self) -> None:
        """Register with the master and wait for the driver's position, feedback and command subscription.

        Raises:
            RosError: no master, or the driver's topics do not appear within ``connect_timeout_s``.
        """
        from ur3hanoi.interface.ros1.env import import_rospy
        from ur3hanoi.interface.ros1.master import MasterUri, master_pid
        from ur3hanoi.interface.ros1.msgs import load_messages
        from ur3hanoi.interface.ros1.watch import MasterWatch, quick_shutdown

        MasterUri.parse(self.master_uri)
        pid = master_pid(self.master_uri, timeout=2.0)
        if pid is None:
            raise RosError(f"no ROS master answers at {self.master_uri}: start `ur3hanoi ros-station` (it starts one) "
                           "or the course's ur3_driver, or set ROS_MASTER_URI")
        self._msgs = msgs = load_messages()
        rospy = self._rospy = import_rospy()
        os.environ["ROS_MASTER_URI"] = self.master_uri
        rospy.init_node("ur3hanoi_solve", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
        quick_shutdown()
        self._pub = rospy.Publisher("/ur3/command", msgs.command, queue_size=10)
        rospy.Subscriber("/ur3/position", msgs.position, self._on_position, tcp_nodelay=True)
        rospy.Subscriber("/ur3/gripper_input", msgs.gripper_input, self._on_gripper, tcp_nodelay=True)
        self._watch = MasterWatch(self.master_uri, pid).start()
        self._await_driver(self.master_uri, "ros-station or the course's ur3_driver")

    def simulated(self) -> bool:
        """True when the driver is ur3hanoi's ``ros-station`` (its node is registered with the master)."""
        from ur3hanoi.interface.ros1.master import node_registered
        from ur3hanoi.interface.ros1.server import NODE_NAME

        return node_registered(self.master_uri, f"/{NODE_NAME}")

    def close(self) -> None:
        """Stop watching the master and unregister the node (not with a master that is gone)."""
        from ur3hanoi.interface.ros1.watch import end_client

        watch, self._watch = self._watch, None
        end_client(watch, self._rospy)

    def _poll(self) -> None:
        """Raise once the master is gone (the callbacks themselves run in rospy's threads)."""
        from ur3hanoi.interface.ros1.watch import raise_if_lost

        raise_if_lost(self._watch, self.master_uri, "the station (or roscore)")

    # ---------------------------------------------------------------------------------------------- transport
    def _subscribed(self) -> bool:
        return bool(self._pub.get_num_connections() > 0)

    def _publish(self, destination: FloatArray, io_0: bool, v: float, a: float) -> Any:
        msg = self._msgs.command(destination=[float(x) for x in destination], v=v, a=a, io_0=io_0)
        self._pub.publish(msg)
        return msg

    def _republish(self, msg: Any) -> None:
        self._pub.publish(msg)
