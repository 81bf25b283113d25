"""How a UR driver's trajectory controller behaves, per ROS version: its default tolerances and the few rules in
which ROS 1's scaled controller and ROS 2's differ. :class:`~ur3hanoi.interface.urdriver.follower.TrajectoryFollower`
and the goal checks (:mod:`ur3hanoi.interface.urdriver.goal`) read everything version-specific from a
:class:`ControllerProfile`; :data:`ROS1_SCALED` is the ROS 1 driver's ``scaled_pos_joint_traj_controller``,
:data:`ROS2_SCALED` the ROS 2 driver's ``scaled_joint_trajectory_controller`` (its binding may refine it).

Sources: ROS 1 ``ur_robot_driver/config/ur3_controllers.yaml`` (URD1 @ 66510fd) and the scaled controller (URSC
``scaled_joint_trajectory_controller.h`` @ c040abb, whose path and goal aborts carry no ``error_string``, unlike the
plain JTC's ``"<joint> path error <v>"``); ROS 2 ``ur_robot_driver/config/ur_controllers.yaml`` and ros2_controllers'
``joint_trajectory_controller.cpp`` (jazzy).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal


@dataclass(frozen=True)
class ControllerProfile:
    """One controller's configuration and version-specific rules.

    Attributes:
        name: for reports (``ros1_scaled``).
        goal_time_s: extra controller time [s] after a trajectory's end to come within the goal tolerances
            (``constraints/goal_time``); a goal's ``goal_time_tolerance`` > 0 replaces it.
        goal_time_zero_waits: True (ROS 2): a goal time of 0 means "no limit" (the goal waits until the arm is in
            tolerance); False (ROS 1): 0 means the goal must be in tolerance when the trajectory ends.
        stopped_velocity_tolerance: the goal's velocity tolerance [rad/s] (every joint).
        path_tolerance_rad, goal_tolerance_rad: per-joint position tolerances [rad] while moving and at the goal
            (``<joint>/trajectory``, ``<joint>/goal``); 0 = not checked.
        stop_trajectory_s: duration [s] of the ramp to rest on a cancel (``stop_trajectory_duration``), lengthened
            where a joint's deceleration limit needs more (see the follower); 0 holds the desired position at once.
        hold_on_path_abort: True (ROS 2): after a path-tolerance abort the arm holds; False (ROS 1): the controller
            keeps following the aborted trajectory.
        sample_one_period_ahead: ROS 1's scaled controller samples the trajectory at ``uptime + period`` while its
            uptime advances by ``period x scaling`` (URSC's ``traj_time``).
        validation: which goal checks and rejections apply (:func:`ur3hanoi.interface.urdriver.goal.check_goal`):
            ``ros1`` (coded rejections: INVALID_JOINTS, INVALID_GOAL with a reason) or ``ros2`` (rejected at
            ``send_goal`` without a code; the reason is only logged).
        reject_nonzero_final_velocity: ROS 2 Jazzy and newer reject a trajectory whose last point moves.
        path_error, goal_error, success_text: the result's ``error_string`` formats; fields ``joint``, ``error``
            [rad] and ``late`` [s]. Empty: the controller sets none.
        speed_scaling_unit: what the driver publishes for a speed scaling of 1 (ROS 1: 1.0; ROS 2: 100.0, percent).
        set_io_waits: True (ROS 2): ``set_io`` answers once the output changed; False (ROS 1): once queued.
        from_measured: True (ROS 2's scaled controller, Humble and Jazzy: ``scaled_joint_trajectory_controller.cpp``
            @ a16a268 lines 134-146 and 280-284, ``interpolate_from_desired_state`` and ``open_loop_control`` false
            by default): a new trajectory starts from the *measured* state at its first sample (no point is
            dropped, a point at ``time_from_start`` 0 is commanded at once), and an abort or a cancel holds the
            measured position (``set_hold_position``); False (ROS 1): from the desired state, past points dropped.
            Kilted and later run ros2_controllers' own JTC with the scaling built in (UR's kilted scaled controller
            only renames a parameter; ros2_controllers kilted ``joint_trajectory_controller.cpp`` lines 305-322,
            1291, 1506): the same rules and texts, so one flag serves Humble to Lyrical.
        deactivated_text: the ``error_string`` of the goal that runs when the controller is stopped because the
            robot program stopped: ROS 2 aborts it (``on_deactivate``, ros2_controllers jazzy
            ``joint_trajectory_controller.cpp`` @ ed360c9 lines 1255-1267, humble @ ad559d9 lines 1055-1067); empty:
            ROS 1 preempts it without a result (``stopping`` -> ``preemptActiveGoal`` -> ``setCanceled``).
    """

    name: str
    goal_time_s: float
    goal_time_zero_waits: bool
    stopped_velocity_tolerance: float
    path_tolerance_rad: float
    goal_tolerance_rad: float
    stop_trajectory_s: float
    hold_on_path_abort: bool
    sample_one_period_ahead: bool
    validation: Literal["ros1", "ros2"]
    reject_nonzero_final_velocity: bool
    path_error: str
    goal_error: str
    success_text: str
    speed_scaling_unit: float
    set_io_waits: bool
    from_measured: bool = False
    deactivated_text: str = ""


ROS1_SCALED = ControllerProfile(
    name="ros1_scaled", goal_time_s=0.6, goal_time_zero_waits=False, stopped_velocity_tolerance=0.05,
    path_tolerance_rad=0.2, goal_tolerance_rad=0.1, stop_trajectory_s=0.5, hold_on_path_abort=False,
    sample_one_period_ahead=True, validation="ros1", reject_nonzero_final_velocity=False,
    path_error="", goal_error="", success_text="", speed_scaling_unit=1.0, set_io_waits=False,
)
"""The ROS 1 driver's ``scaled_pos_joint_traj_controller`` (see the module docstring)."""

ROS2_SCALED = ControllerProfile(
    name="ros2_scaled", goal_time_s=0.0, goal_time_zero_waits=True, stopped_velocity_tolerance=0.2,
    path_tolerance_rad=0.2, goal_tolerance_rad=0.1, stop_trajectory_s=0.0, hold_on_path_abort=True,
    sample_one_period_ahead=False, validation="ros2", reject_nonzero_final_velocity=True,
    path_error="Aborted due to path tolerance violation",
    goal_error="Aborted due to goal_time_tolerance exceeding by {late:f} seconds",
    success_text="Goal successfully reached!", speed_scaling_unit=100.0, set_io_waits=True, from_measured=True,
    deactivated_text="Current goal cancelled during deactivate transition.",
)
"""The ROS 2 driver's ``scaled_joint_trajectory_controller`` on Jazzy (ros2_controllers' texts)."""

JTC_ERROR_TEXTS = {"path_error": "{joint} path error {error:f}", "goal_error": "{joint} goal error {error:f}"}
"""The plain ROS 1 JTC's ``error_string`` formats (``std::to_string`` of the error), for a profile of it."""

NOT_RUNNING = "Can't accept new action goals. Controller is not running."
"""What both controllers log when a goal arrives while they are stopped (ROS 1 ``goalCB``: INVALID_GOAL without an
``error_string``; ROS 2 ``goal_received_callback``, jazzy line 1407-1411: rejected at ``send_goal``)."""
