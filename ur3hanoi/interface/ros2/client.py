"""The arm as seen through the ROS 2 course topics: ``ur3e/command`` out, ``ur3e/position`` and
``ur3e/gripper_input`` in (``ros2-station`` or the course's real-robot bridge).

:class:`Ros2Arm` is the transport-neutral :class:`ur3hanoi.interface.course.client.TopicArm` (moves, waits, suction
checks, timeouts) bound to Cyclone DDS, so :func:`ur3hanoi.interface.course.solve.run_lab_solve` drives it with the same
suction checks and halt as ``ros-solve``. It works in the controller convention like the rest of ur3hanoi and converts
at the topic (the bridge's course convention by default, :mod:`ur3hanoi.robot.convention`). A move is done when every
joint is within ``tolerance_rad`` (0.0008 rad, what ENME480 student programs wait for); ``is_ready`` is not used (the
bridge always sends true). ``held`` is ``dig_in`` bit 0. The readers are polled in the waiting loops.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.interface.course.client import ArmConfig, TopicArm, Topics
from ur3hanoi.robot.convention import from_controller, to_controller

TOPICS = Topics(command="ur3e/command", position="ur3e/position", gripper="ur3e/gripper_input", digital="dig_in",
                analog="a_in0")


@dataclass(frozen=True)
class Ros2ArmConfig(ArmConfig):
    """How the client commands and waits (:class:`ur3hanoi.interface.course.client.ArmConfig`); ``tolerance_rad`` is the
    ENME480 programs' 0.0008 rad, ``convention`` the topics' joint convention."""

    v: float = 1.0
    a: float = 1.0
    tolerance_rad: float = 8e-4
    convention: str = "course"


class Ros2Arm(TopicArm):
    """The robot through the ROS 2 course topics. Call :meth:`connect` first, :meth:`close` at the end.

    Args:
        config: command speed, tolerances, timeouts, convention.
        domain_id, network: the DDS domain and network (:class:`ur3hanoi.interface.ros2.dds.Ros2Node`).
        log: where re-publish notices go.
    """

    config: Ros2ArmConfig

    def __init__(self, config: Ros2ArmConfig | None = None, domain_id: int = 0, network: str = "loopback",
                 log: Callable[[str], None] | None = None) -> None:
        super().__init__(config if config is not None else Ros2ArmConfig(), TOPICS, log)
        self.domain_id = domain_id
        self.network = network
        self._node: Any = None
        self._pub: Any = None
        self._readers: tuple[Any, Any] | None = None
        self._spawn: Any = None

    def connect(self) -> None:
        """Join the domain and wait for the bridge's position and feedback and a ``ur3e/command`` subscriber.

        Raises:
            DriverError: they do not appear within ``connect_timeout_s``.
        """
        from ur3hanoi.interface.ros2.dds import Ros2Node
        from ur3hanoi.interface.ros2.msgs import CommandUR3e, GripperInput, Int32, PositionUR3e
        from ur3hanoi.interface.ros2.server import TOPIC_SPAWN

        self._node = node = Ros2Node("ur3hanoi_solve", self.domain_id, self.network)
        self._pub = node.publisher(TOPICS.command, CommandUR3e)
        self._readers = (node.subscription(TOPICS.position, PositionUR3e),
                         node.subscription(TOPICS.gripper, GripperInput))
        # Never written: only ur3hanoi's station subscribes it, so a match says there is no pendant (simulated()).
        self._spawn = node.publisher(TOPIC_SPAWN, Int32)
        node.announce()
        self._await_driver(f"ROS_DOMAIN_ID {self.domain_id} ({self.network})", "ros2-station or the course's bridge")

    def simulated(self) -> bool:
        """True when the driver is ur3hanoi's ``ros2-station`` (it subscribes ``ur3hanoi/spawn``)."""
        return self._spawn is not None and len(self._spawn.get_matched_subscriptions()) > 0

    def close(self) -> None:
        if self._node is not None:
            self._node.close()
            self._node = None

    def _poll(self) -> None:
        """Take what arrived; keep the newest position and feedback."""
        if self._readers is None:
            return
        pos, grip = self._readers
        for msg in pos.take(N=100):
            if hasattr(msg, "position"):
                q = np.array(msg.position, dtype=float)
                self._position(to_controller(q, self.config.convention) if q.shape == (6,) else q)
        for msg in grip.take(N=100):
            if hasattr(msg, "dig_in"):
                self._feedback(int(msg.dig_in), float(msg.a_in0))

    def _subscribed(self) -> bool:
        return len(self._pub.get_matched_subscriptions()) > 0

    def _publish(self, destination: FloatArray, io_0: bool, v: float, a: float) -> Any:
        from ur3hanoi.interface.ros2.msgs import CommandUR3e

        dest = from_controller(np.asarray(destination, dtype=float), self.config.convention)
        msg = CommandUR3e(destination=[float(x) for x in dest], v=v, a=a, io_0=io_0)
        self._pub.write(msg)
        return msg

    def _republish(self, msg: Any) -> None:
        self._pub.write(msg)
