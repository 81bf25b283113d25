"""``teach --driver ur`` and ``check-arm`` on the official ROS 2 UR driver: :class:`RclpyCellLink`.

The solve's transport (:class:`~ur3hanoi.interface.ros2.ur_client.RclpyDriverTransport`) with what the commands before
a solve need (:class:`ur3hanoi.interface.urdriver.cell.CellLink`; the transport itself follows the driver's latched
``/io_and_status_controller/robot_program_running``): every ``/joint_states`` kept for the last seconds
(:class:`~ur3hanoi.interface.urdriver.cell.JointHistory`), and whether the driver is ur3hanoi's
``ros2-station --driver ur`` (its node in the graph).
"""

from __future__ import annotations

from ur3hanoi.interface.ros2.ur_client import RclpyDriverTransport
from ur3hanoi.interface.urdriver.cell import JointHistory

LIST_CONTROLLERS = "/controller_manager/list_controllers"
"""``controller_manager_msgs/srv/ListControllers``: every controller with its state."""
SERVICE_WAIT_S = 1.0
"""[s] how long :meth:`RclpyCellLink.controller_state` waits for the controller manager's answer."""
GRAPH_WAIT_S = 2.0
"""[s] how long :meth:`RclpyCellLink.simulated` waits for the graph to name the driver's node."""


class RclpyCellLink(RclpyDriverTransport):
    """The ROS 2 UR driver for teach and the check (see the module docstring)."""

    def __init__(self, distro: str, domain_id: int | None = None, network: str = "loopback",
                 connect_timeout_s: float = 10.0) -> None:
        super().__init__(distro, domain_id, network, connect_timeout_s)
        self.history = self.record = JointHistory()
        self.action = self.names.follow_joint_trajectory

    def program_running(self) -> bool | None:
        return self.latest().program_running

    def controller_state(self) -> str | None:
        """The trajectory controller's state as the controller manager lists it (``active``, ``inactive``,
        ``not loaded``), or None when no controller manager answers within :data:`SERVICE_WAIT_S`."""
        import threading

        from ur3hanoi.interface.ros2.errors import RclpyUnavailableError
        from ur3hanoi.interface.ros2.rclpy_env import import_interfaces

        try:
            (cm_srv,) = import_interfaces("controller_manager_msgs.srv")
        except RclpyUnavailableError:
            return None
        client = self.node.create_client(cm_srv.ListControllers, LIST_CONTROLLERS)
        try:
            if not client.wait_for_service(timeout_sec=SERVICE_WAIT_S):
                return None
            done = threading.Event()
            future = client.call_async(cm_srv.ListControllers.Request())
            future.add_done_callback(lambda _: done.set())
            if not done.wait(SERVICE_WAIT_S) or future.result() is None:
                return None
            wanted = self.action.strip("/").split("/")[0]
            states = {str(c.name): str(c.state) for c in future.result().controller}
            return states.get(wanted, "not loaded")
        finally:
            self.node.destroy_client(client)

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
