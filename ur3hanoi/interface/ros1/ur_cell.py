"""``teach --driver ur`` and ``check-arm`` on the official ROS 1 UR driver: :class:`RosCellLink`.

The solve's transport (:class:`~ur3hanoi.interface.ros1.ur_client.RosDriverTransport`) with what the commands before a
solve need (:class:`ur3hanoi.interface.urdriver.cell.CellLink`): every ``/joint_states`` kept for the last seconds
(:class:`~ur3hanoi.interface.urdriver.cell.JointHistory`), the driver's latched
``/ur_hardware_interface/robot_program_running`` (``std_msgs/Bool``), and whether the driver is ur3hanoi's
``ros-station --driver ur`` (its node registered with the master).
"""

from __future__ import annotations

import importlib
from typing import Any

from ur3hanoi.interface.ros1.ur_client import RosDriverTransport
from ur3hanoi.interface.urdriver.cell import JointHistory

PROGRAM_RUNNING = "/ur_hardware_interface/robot_program_running"
"""The ROS 1 driver's latched ``std_msgs/Bool``: whether the External Control program runs."""


class RosCellLink(RosDriverTransport):
    """The ROS 1 UR driver for teach and the check (see the module docstring)."""

    def __init__(self, master_uri: str | None = None, connect_timeout_s: float = 15.0) -> None:
        super().__init__(master_uri, connect_timeout_s)
        self.history = self.record = JointHistory()
        self._program: bool | None = None

    def connect(self) -> None:
        super().connect()
        std_msgs = importlib.import_module("std_msgs.msg")
        self._rospy.Subscriber(PROGRAM_RUNNING, std_msgs.Bool, self._on_program, tcp_nodelay=True)

    def _on_program(self, msg: Any) -> None:
        self._program = bool(msg.data)

    def program_running(self) -> bool | None:
        return self._program

    def simulated(self) -> bool:
        from ur3hanoi.interface.ros1.master import node_registered
        from ur3hanoi.interface.ros1.server import NODE_NAME

        return node_registered(self.master_uri, f"/{NODE_NAME}")
