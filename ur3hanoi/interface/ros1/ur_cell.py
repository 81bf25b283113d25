"""``teach --driver ur`` and ``check-arm`` on the official ROS 1 UR driver: :class:`RosCellLink`.

The solve's transport (:class:`~ur3hanoi.interface.ros1.ur_client.RosDriverTransport`, which also follows the driver's
latched ``/ur_hardware_interface/robot_program_running``) with what the commands before a solve need
(:class:`ur3hanoi.interface.urdriver.cell.CellLink`): every ``/joint_states`` kept for the last seconds
(:class:`~ur3hanoi.interface.urdriver.cell.JointHistory`), and whether the driver is ur3hanoi's
``ros-station --driver ur`` (its node registered with the master).
"""

from __future__ import annotations

import logging

from ur3hanoi.interface.ros1.ur_client import RosDriverTransport
from ur3hanoi.interface.urdriver.cell import JointHistory
from ur3hanoi.interface.urdriver.facts import ROS1

LIST_CONTROLLERS = "/controller_manager/list_controllers"
"""``controller_manager_msgs/ListControllers``: every controller with its state (ros_control: ``running``)."""


class _OldGoalFilter(logging.Filter):
    """Drops actionlib's "on a goal handle that we're not tracking": ``SimpleActionClient`` tracks only the newest
    goal, and the driver goes on reporting the previous jog step's (succeeded) goal for a while after the next one is
    sent; the line would land in teach's live screen."""

    def filter(self, record: logging.LogRecord) -> bool:
        return "on a goal handle that we're not tracking" not in record.getMessage()


class RosCellLink(RosDriverTransport):
    """The ROS 1 UR driver for teach and the check (see the module docstring)."""

    def __init__(self, master_uri: str | None = None, connect_timeout_s: float = 15.0) -> None:
        super().__init__(master_uri, connect_timeout_s)
        self.history = self.record = JointHistory()
        self.action = ROS1.follow_joint_trajectory

    def connect(self) -> None:
        super().connect()
        logging.getLogger("rosout").addFilter(_OldGoalFilter())

    def program_running(self) -> bool | None:
        return self.latest().program_running

    def controller_state(self) -> str | None:
        """The trajectory controller's state in ``/controller_manager/list_controllers`` (``running``, ``stopped``,
        ``initialized``, ``not loaded``), or None when no controller manager answers within 1 s."""
        from ur3hanoi.interface.ros1.ur_packages import service_classes

        rospy = self._rospy
        cls = service_classes()["controller_manager_msgs/ListControllers"]
        proxy = rospy.ServiceProxy(LIST_CONTROLLERS, cls)
        try:
            proxy.wait_for_service(1.0)
            answer = proxy()
        except (rospy.ROSException, rospy.ServiceException):
            return None
        finally:
            proxy.close()
        wanted = self.action.strip("/").split("/")[0]
        states = {str(c.name): str(c.state) for c in answer.controller}
        return states.get(wanted, "not loaded")

    def simulated(self) -> bool:
        from ur3hanoi.interface.ros1.master import node_registered
        from ur3hanoi.interface.ros1.server import NODE_NAME

        return node_registered(self.master_uri, f"/{NODE_NAME}")
