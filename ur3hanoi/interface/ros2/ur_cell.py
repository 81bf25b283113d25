"""``teach --driver ur`` and ``check-arm`` on the official ROS 2 UR driver: :class:`RclpyCellLink`.

The solve's transport (:class:`~ur3hanoi.interface.ros2.ur_client.RclpyDriverTransport`) with what the commands before
a solve need (:class:`ur3hanoi.interface.urdriver.cell.CellLink`): every ``/joint_states`` kept for the last seconds
(:class:`~ur3hanoi.interface.urdriver.cell.JointHistory`), the driver's ``/io_and_status_controller/
robot_program_running`` (``std_msgs/Bool``, published transient-local: the subscription asks the same, so it gets the
last value at once), and whether the driver is ur3hanoi's ``ros2-station --driver ur`` (its node in the graph).
"""

from __future__ import annotations

from typing import Any

from ur3hanoi.interface.ros2.rclpy_env import import_interfaces
from ur3hanoi.interface.ros2.ur_client import RclpyDriverTransport
from ur3hanoi.interface.urdriver.cell import JointHistory

PROGRAM_RUNNING = "/io_and_status_controller/robot_program_running"
"""The ROS 2 driver's latched ``std_msgs/Bool``: whether the External Control program runs."""
GRAPH_WAIT_S = 2.0
"""[s] how long :meth:`RclpyCellLink.simulated` waits for the graph to name the driver's node."""


class RclpyCellLink(RclpyDriverTransport):
    """The ROS 2 UR driver for teach and the check (see the module docstring)."""

    def __init__(self, distro: str, domain_id: int | None = None, network: str = "loopback",
                 connect_timeout_s: float = 10.0) -> None:
        super().__init__(distro, domain_id, network, connect_timeout_s)
        self.history = self.record = JointHistory()
        self._program: bool | None = None

    def _start(self) -> None:
        super()._start()
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy

        (std_msgs,) = import_interfaces("std_msgs.msg")
        latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL)
        self.node.create_subscription(std_msgs.Bool, PROGRAM_RUNNING, self._on_program, latched)

    def _on_program(self, msg: Any) -> None:
        self._program = bool(msg.data)

    def program_running(self) -> bool | None:
        return self._program

    def simulated(self) -> bool:
        """True when the node publishing ``/joint_states`` is ur3hanoi's station (the graph learns a node's name
        after its topics: waits for it, at most :data:`GRAPH_WAIT_S`)."""
        import time

        from ur3hanoi.interface.ros2.ur_station import NODE_NAME

        end = time.monotonic() + GRAPH_WAIT_S
        while True:
            nodes = {i.node_name for i in self.node.get_publishers_info_by_topic(self.names.joint_states)}
            if (nodes and "_NODE_NAME_UNKNOWN_" not in nodes) or time.monotonic() > end:
                return NODE_NAME in nodes
            time.sleep(0.05)
