"""The settings of a simulated lab, one type for both drivers of the task scene: ``solve``'s plan executor
(:func:`ur3hanoi.sim.run_plan`) and the ``movej`` world the ROS servers run (:class:`ur3hanoi.sim.MoveJWorld`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ur3hanoi.sim.scene import SceneConfig
from ur3hanoi.sim.suction import SuctionConfig


@dataclass(frozen=True)
class SimConfig:
    """Settings of a simulated lab. Both drivers use the scene, the servo and the checks; ``halt_speed_scale``,
    ``settle_s`` and ``knock_tolerance_m`` are ``solve``'s (whose control period is the plan's); ``period_s``,
    ``settle_tolerance_rad`` and ``drop_delay_s`` the ``movej`` world's.

    Attributes:
        scene, suction: see :class:`~ur3hanoi.sim.SceneConfig`, :class:`~ur3hanoi.sim.SuctionConfig`.
        seed: seeds the feedback noise (``AIN0``).
        accel_feedforward: add the arm's own inertia times the reference acceleration, ``M(q) qdd_ref / kp``, to
            the servo command (:class:`~ur3hanoi.sim.servo.JointServo`: the UR controller moves on a model of its
            arm; velocity feed-forward alone left the cup ~0.2 mm below the contact pose at the end of a place,
            pressing the block into the stack).
        place_tolerance_m: a block is in a slot when its centre is within this distance [m] of the slot's centre.
        home_tolerance_rad: "at home" when every joint is within this angle [rad] of the home pose.
        halt_speed_scale: ``solve``: fraction of the joint speed limits used to stop and to return home after a
            fault.
        settle_s: ``solve``: time [s] simulated at rest after the last sample (blocks settle, the servo
            converges).
        knock_tolerance_m: ``solve``: after a halt, a block that rested when the fault was detected and has since
            moved farther than this [m] was knocked (e.g. by the dropped block) and is reported.
        period_s: the world's control period [s]; a multiple of the physics step. 8 ms: the CB3 controller's
            125 Hz (the course driver publishes ``ur3/position`` every 8 ms).
        settle_tolerance_rad: the world's arm is "at" its destination when every joint is within this angle [rad]
            (the lab's ``move_arm`` waits for 0.0005 rad).
        drop_delay_s: the world: with a drop injected on a grasp, the block falls this long [s] into the next
            motion.
    """

    scene: SceneConfig = field(default_factory=SceneConfig)
    suction: SuctionConfig = field(default_factory=SuctionConfig)
    seed: int = 0
    accel_feedforward: bool = True
    place_tolerance_m: float = 0.005
    home_tolerance_rad: float = 0.01
    halt_speed_scale: float = 0.5
    settle_s: float = 0.3
    knock_tolerance_m: float = 0.001
    period_s: float = 0.008
    settle_tolerance_rad: float = 5e-4
    drop_delay_s: float = 0.2
