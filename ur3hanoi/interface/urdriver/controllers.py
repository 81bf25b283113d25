"""The UR ROS 2 driver's ``controller_manager`` and its ``controller_stopper``, without a middleware: which
controllers are loaded, which are active, and how ``switch_controller`` and the External Control program change that.

:class:`ControllerManager` answers ``list_controllers`` and ``switch_controller`` as ros2_control's
``controller_manager.cpp`` does (jazzy @ 9ffbf97, ``switch_controller`` lines 1895-2370): STRICT fails the whole
switch on an unknown controller ("Could not activate controller with name 'x' because no controller with this name
exists"), on activating an active one or deactivating an inactive one ("Could not activate controller 'x' since it
is already active"); BEST_EFFORT skips those and fails only when nothing is left to do; two active controllers may
not claim one command interface ("Resource conflict for controller 'x'. Command interface 'y' is already claimed.");
the UR hardware allows one motion mode at a time (position, velocity or passthrough: ``hardware_interface.cpp``
@ a16a268 ``prepare_command_mode_switch``, "Could not switch controllers since prepare command mode switch was
rejected."). AUTO and FORCE_AUTO are BEST_EFFORT (the manager logs that they are not implemented).

The controllers and their states are ``ur_control.launch.py``'s (jazzy @ a16a268 lines 151-235): the broadcasters and
``io_and_status_controller`` active and kept when the program stops (``consistent_controllers``), the initial
motion controller active, the other motion controllers loaded and inactive. :meth:`ControllerManager.program` is the
``controller_stopper`` (``controller_stopper.cpp``): when the program stops it deactivates every active controller
that is not a consistent one and remembers them; when it runs again it activates those.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS

BEST_EFFORT, STRICT, AUTO, FORCE_AUTO = 1, 2, 3, 4
"""``SwitchController.Request`` strictness values."""


@dataclass(frozen=True)
class Controller:
    """A loaded controller: ``name``, its class (``type``), the command interfaces it claims when active, whether
    it serves a ``follow_joint_trajectory`` action (its goals drive the station's arm), and its motion mode (the UR
    hardware allows one at a time; empty: claims nothing)."""

    name: str
    type: str
    mode: str = ""
    action: bool = False

    @property
    def interfaces(self) -> tuple[str, ...]:
        if self.mode in ("position", "velocity"):
            return tuple(f"{j}/{self.mode}" for j in CONTROLLER_JOINTS)
        if self.mode == "passthrough":
            return tuple(f"trajectory_passthrough/setpoint_positions_{i}" for i in range(len(CONTROLLER_JOINTS)))
        return ()


BROADCASTERS = (
    Controller("joint_state_broadcaster", "joint_state_broadcaster/JointStateBroadcaster"),
    Controller("io_and_status_controller", "ur_controllers/GPIOController"),
    Controller("speed_scaling_state_broadcaster", "ur_controllers/SpeedScalingStateBroadcaster"),
    Controller("force_torque_sensor_broadcaster", "force_torque_sensor_broadcaster/ForceTorqueSensorBroadcaster"),
)
"""Active from the start and kept while the program is stopped (``consistent_controllers``)."""

MOTION = (
    Controller("scaled_joint_trajectory_controller", "ur_controllers/ScaledJointTrajectoryController", "position",
               True),
    Controller("joint_trajectory_controller", "joint_trajectory_controller/JointTrajectoryController", "position",
               True),
    Controller("passthrough_trajectory_controller", "ur_controllers/PassthroughTrajectoryController", "passthrough",
               True),
    Controller("forward_position_controller", "position_controllers/JointGroupPositionController", "position"),
    Controller("forward_velocity_controller", "velocity_controllers/JointGroupVelocityController", "velocity"),
)
"""The motion controllers UR's examples and tests name (loaded inactive but the initial one)."""


class ControllerManager:
    """The loaded controllers and their states (see the module docstring).

    Args:
        initial: the motion controller active at start (``initial_joint_controller``).
        motion: the motion controllers loaded (Lyrical has no scaled one: the caller leaves it out).
    """

    def __init__(self, initial: str, motion: Sequence[Controller] = MOTION) -> None:
        if initial == "joint_trajectory_controller":  # Lyrical: scaling built in, the scaled one is gone
            motion = [c for c in motion if c.name != "scaled_joint_trajectory_controller"]
        self.controllers = {c.name: c for c in (*BROADCASTERS, *motion)}
        self.consistent = {c.name for c in BROADCASTERS}
        self.active = {*self.consistent, initial}
        self.stopped: list[str] = []  # what the controller_stopper deactivated

    def listing(self) -> list[tuple[Controller, str]]:
        """``list_controllers``: every controller with its state (``active`` or ``inactive``), in load order."""
        return [(c, "active" if c.name in self.active else "inactive") for c in self.controllers.values()]

    def trajectory_controller(self) -> str | None:
        """The active controller whose action drives the arm, if any."""
        return next((n for n in self.active if self.controllers[n].action), None)

    def switch(self, activate: Sequence[str], deactivate: Sequence[str], strictness: int) -> tuple[bool, str]:
        """``switch_controller``: (``ok``, ``message``); nothing changes unless ``ok``."""
        strict = strictness == STRICT
        lists = {"activate": list(dict.fromkeys(activate)), "deactivate": list(dict.fromkeys(deactivate))}
        messages: list[str] = []
        for action, names in lists.items():
            for name in list(names):
                if name not in self.controllers:
                    text = f"Could not {action} controller with name '{name}' because no controller with this name " \
                           "exists"
                    if strict:
                        return False, text
                    messages.append(text)
                    names.remove(name)
        if not lists["activate"] and not lists["deactivate"] and messages:
            return False, "\n".join(messages)
        for name in list(lists["deactivate"]):
            if name not in self.active:
                text = f"Could not deactivate controller '{name}' since it is not active"
                if strict:
                    return False, text
                lists["deactivate"].remove(name)
        for name in list(lists["activate"]):
            if name in self.active and name not in lists["deactivate"]:
                text = f"Could not activate controller '{name}' since it is already active"
                if strict:
                    return False, text
                lists["activate"].remove(name)
        after = (self.active - set(lists["deactivate"])) | set(lists["activate"])
        conflict = self._conflict(after, lists["activate"])
        if conflict is not None:
            return False, conflict
        self.active = after
        return True, ""

    def _conflict(self, after: set[str], activated: list[str]) -> str | None:
        claimed: dict[str, str] = {}
        for name in sorted(after, key=lambda n: n in activated):  # the ones staying claim first
            for interface in self.controllers[name].interfaces:
                if interface in claimed:
                    return f"Resource conflict for controller '{name}'. Command interface '{interface}' is " \
                           "already claimed."
                claimed[interface] = name
        if len({self.controllers[n].mode for n in after} - {""}) > 1:
            return "Could not switch controllers since prepare command mode switch was rejected."
        return None

    def program(self, running: bool) -> None:
        """The ``controller_stopper``: the program stopped (deactivate every non-consistent controller, remember
        them) or runs again (activate those)."""
        if not running:
            self.stopped = [n for n in self.controllers if n in self.active and n not in self.consistent]
            self.active -= set(self.stopped)
        else:
            self.active |= set(self.stopped)
            self.stopped = []


ROS1_LOADABLE = {
    "joint_state_controller": ("joint_state_controller/JointStateController", ""),
    "speed_scaling_state_controller": ("scaled_controllers/SpeedScalingStateController", ""),
    "force_torque_sensor_controller": ("force_torque_sensor_controller/ForceTorqueSensorController", ""),
    "robot_status_controller": ("industrial_robot_status_controller/IndustrialRobotStatusController", ""),
    "scaled_pos_joint_traj_controller": ("position_controllers/ScaledJointTrajectoryController", "position"),
    "pos_joint_traj_controller": ("position_controllers/JointTrajectoryController", "position"),
    "scaled_vel_joint_traj_controller": ("velocity_controllers/ScaledJointTrajectoryController", "velocity"),
    "vel_joint_traj_controller": ("velocity_controllers/JointTrajectoryController", "velocity"),
    "joint_group_vel_controller": ("velocity_controllers/JointGroupVelocityController", "velocity"),
    "forward_joint_traj_controller": ("pass_through_controllers/JointTrajectoryController", "forward"),
    "forward_cartesian_traj_controller": ("pass_through_controllers/CartesianTrajectoryController", "forward"),
    "twist_controller": ("ros_controllers_cartesian/TwistController", "velocity"),
    "pose_based_cartesian_traj_controller": ("pose_controllers/CartesianTrajectoryController", "pose"),
    "joint_based_cartesian_traj_controller": ("position_controllers/CartesianTrajectoryController", "position"),
}
"""ROS 1: what ``ur3_controllers.yaml`` (URD1 @ 66510fd) configures: name -> (type, the joints' interface it claims;
empty: none)."""


class Ros1ControllerManager:
    """ROS 1's ``controller_manager`` (ros_control noetic-devel ``controller_manager.cpp``: ``switchController``,
    ``loadController``) with ``ur3_bringup.launch``'s controllers (URD1 @ 66510fd: running
    ``joint_state_controller scaled_pos_joint_traj_controller speed_scaling_state_controller
    force_torque_sensor_controller``, loaded stopped ``pos_joint_traj_controller joint_group_vel_controller``), UR's
    hardware interface (``prepareSwitch``: no controller that claims joints starts while the robot program is
    stopped) and its ``controller_stopper`` (consistent: ``joint_state_controller speed_scaling_state_controller
    force_torque_sensor_controller robot_status_controller``). The answers carry only ``ok``; the reasons go to the
    log (:attr:`last_error`), as the ROS 1 manager's ``ROS_ERROR``."""

    consistent = ("joint_state_controller", "speed_scaling_state_controller", "force_torque_sensor_controller",
                  "robot_status_controller")

    def __init__(self) -> None:
        running = ("joint_state_controller", "scaled_pos_joint_traj_controller", "speed_scaling_state_controller",
                   "force_torque_sensor_controller")
        self.states = {n: "running" for n in running} | {n: "stopped" for n in ("pos_joint_traj_controller",
                                                                               "joint_group_vel_controller")}
        self.stopped: list[str] = []
        self.last_error = ""

    def trajectory_controller(self) -> str | None:
        """The stand-in serves the scaled position controller's action only: that one, when it runs."""
        return "scaled_pos_joint_traj_controller" if self.states.get("scaled_pos_joint_traj_controller") == \
            "running" else None

    def listing(self) -> list[tuple[str, str, str, tuple[str, ...]]]:
        """``list_controllers``: (name, state, type, claimed joints) of every loaded controller."""
        return [(n, s, ROS1_LOADABLE[n][0], CONTROLLER_JOINTS if ROS1_LOADABLE[n][1] else ())
                for n, s in self.states.items()]

    def load(self, name: str) -> bool:
        """``load_controller``."""
        if name in self.states:
            self.last_error = f"A controller named '{name}' was already loaded inside the controller manager"
        elif name not in ROS1_LOADABLE:
            self.last_error = f"Could not load controller '{name}' because the type was not specified. Did you " \
                              "load the controller configuration on the parameter server (namespace: " \
                              f"'/{name}')?"
        else:
            self.states[name] = "initialized"
            return True
        return False

    def switch(self, start: Sequence[str], stop: Sequence[str], strictness: int, program_running: bool) -> bool:
        """``switch_controller``: ``ok``; nothing changes unless it is true."""
        strict = strictness == STRICT
        lists = {"start": list(dict.fromkeys(start)), "stop": list(dict.fromkeys(stop))}
        for action, names in lists.items():
            for name in list(names):
                running = self.states.get(name) == "running"
                why = (f"Could not {action} controller with name '{name}' because no controller with this name "
                       "exists" if name not in self.states else
                       f"Could not stop controller '{name}' since it is not running" if action == "stop" and not running
                       else f"Could not start controller '{name}' since it is already running"
                       if action == "start" and running and name not in lists["stop"] else "")
                if why:
                    self.last_error = why
                    if strict:
                        return False
                    names.remove(name)
        after = {n for n, s in self.states.items() if s == "running"} - set(lists["stop"]) | set(lists["start"])
        if sum(1 for n in after if ROS1_LOADABLE[n][1]) > 1:
            self.last_error = "Could not switch controllers, due to resource conflict"
            return False
        claiming = [n for n in lists["start"] if ROS1_LOADABLE[n][1]]
        if claiming and not program_running:
            self.last_error = "Robot control is currently inactive. Starting controllers that claim resources is " \
                              f"currently not possible. Not starting controller '{claiming[0]}'"
            return False
        for n in lists["stop"]:
            self.states[n] = "stopped"
        for n in lists["start"]:
            self.states[n] = "running"
        return True

    def program(self, running: bool) -> None:
        """The ``controller_stopper``: stop the non-consistent running controllers, or start them again."""
        if not running:
            self.stopped = [n for n, s in self.states.items() if s == "running" and n not in self.consistent]
            for n in self.stopped:
                self.states[n] = "stopped"
        else:
            for n in self.stopped:
                self.states[n] = "running"
            self.stopped = []
