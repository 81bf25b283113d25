"""The course interface's simulated station: the task scene driven like the UR controller drives the arm, one
``movej`` command after another.

:class:`MoveJWorld` is a :class:`~ur3hanoi.sim.task_world.TaskWorld` (scene, servo, suction, blocks) whose joint
reference is the running ``movej`` (:mod:`ur3hanoi.robot.movej`): each :meth:`~MoveJWorld.step` advances one control
period, the reference sample goes through the servo law ``solve`` uses too (:class:`~ur3hanoi.sim.servo.JointServo`:
interpolation, velocity and acceleration feed-forward), the physics runs, the suction grasps a block in reach.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.movej import MoveJ, MoveJReference
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.task_world import EVENTS_KEPT, TaskWorld, WorldEvent
from ur3hanoi.station.calibration import Station


class MoveJWorld(TaskWorld):
    """The simulated arm, suction and blocks of a station, driven by ``movej`` commands (see the module docstring;
    the arguments are :class:`~ur3hanoi.sim.task_world.TaskWorld`'s)."""

    def __init__(self, station: Station, start: int, n_blocks: int, removed: int | None = None,
                 config: SimConfig | None = None, drop_on_grasp: int | None = None) -> None:
        self.reference = MoveJReference(station.q_home_array, station.limits.v_max, station.limits.a_max)
        super().__init__(station, start, n_blocks, removed, config, drop_on_grasp)

    @property
    def target(self) -> FloatArray:
        """Destination of the current (or last) move [rad]."""
        return self.reference.target

    @property
    def moving(self) -> bool:
        """True while a ``movej`` profile runs."""
        return self.reference.motion is not None

    def error_to_target(self) -> float:
        """Largest joint distance [rad] between the measured angles and the current destination."""
        return float(np.max(np.abs(self.q - self.target)))

    @property
    def settled(self) -> bool:
        """No profile running and every joint within ``settle_tolerance_rad`` of the destination."""
        return not self.moving and self.error_to_target() <= self.config.settle_tolerance_rad

    def begin(self, destination: Sequence[float], v: float, a: float, suction: bool) -> MoveJ:
        """Switch the suction on or off and start ``movej(destination, a, v)`` (destination [rad], ``v`` [rad/s],
        ``a`` [rad/s^2], capped at the station's limits) from the current reference."""
        self.set_suction(suction)
        return self.reference.begin(destination, v, a)

    def step(self) -> None:
        """Advance one control period: suction grasp, injected drop, then the servo to the next reference sample
        (physics)."""
        sample = self.reference.advance(self.config.period_s)
        self._update_suction(self.reference.t if self.moving else None)
        if sample is None:
            self.servo.hold(self.reference.q)
        else:
            self.servo.track(*sample)


__all__ = ["EVENTS_KEPT", "MoveJWorld", "WorldEvent"]
