"""The course protocol's station without its transport: the simulated arm under the UR controller's ``movej``.

:class:`CourseStation` is a :class:`~ur3hanoi.interface.common.station.ServerCore` (real-time loop, inbox,
rate-limited log, report, rendering) whose world is :class:`~ur3hanoi.sim.world.MoveJWorld` driven by a
:class:`~ur3hanoi.interface.course.controller.Controller` (the command FIFO, ``isReady``, the settle measurements;
its records bounded). The bindings (:class:`ur3hanoi.interface.ros1.server.RosServer` on rospy,
:class:`ur3hanoi.interface.ros2.server.Ros2Server` on Cyclone DDS) subclass it. Its report's motion sections:
``commands`` (counts), ``executed`` (with duration, settle time and rest error) and ``rejected``; ``final.ready``.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from ur3hanoi.interface.common.station import ServerCore

if TYPE_CHECKING:
    from ur3hanoi.sim.config import SimConfig
    from ur3hanoi.sim.world import MoveJWorld


class CourseStation(ServerCore["MoveJWorld"]):
    """The course's topics' station: command messages (``destination``, ``v``, ``a``, ``io_0``) become ``movej``
    moves (see the module docstring)."""

    def _build_world(self, config: SimConfig, n_blocks: int) -> MoveJWorld:
        """The simulated station and what drives it: the course's ``movej`` controller."""
        from ur3hanoi.interface.course.controller import Controller
        from ur3hanoi.sim.world import MoveJWorld

        opts = self.options
        world = MoveJWorld(self.station, opts.start, n_blocks, opts.removed, config, opts.drop_on_grasp)
        self.controller = Controller(world)
        return world

    def _command(self, msg: Any) -> None:
        """Queue one command message or raise :class:`~ur3hanoi.interface.common.errors.CommandError` (recorded
        by the controller)."""
        self.controller.submit(msg.destination, msg.v, msg.a, msg.io_0)

    def _dropped(self, kind: str, reason: str) -> None:
        """A message of ``kind`` the full inbox refused: a command is recorded as refused."""
        if kind == "command":
            self.controller.refuse(reason)

    def _step(self) -> None:
        """One controller and world step."""
        self.controller.cycle()

    def _report_motion(self) -> dict[str, Any]:
        """The report's sections on what was commanded: the controller's commands."""
        return {"commands": self.controller.summary(),
                "executed": [m.as_dict() for m in self.controller.executed],
                "rejected": [r.as_dict() for r in self.controller.rejected]}

    def _report_final(self) -> dict[str, Any]:
        """The controller's part of the report's ``final`` section."""
        return {"ready": self.controller.ready}
