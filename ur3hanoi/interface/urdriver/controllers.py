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
