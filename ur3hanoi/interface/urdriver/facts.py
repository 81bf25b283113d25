"""The official Universal Robots drivers' interface, as numbers and names: one home for each (the sources are
``../shared/lab/ur-driver-interface.md``, sections 1-3).

- :class:`ErrorCode`: ``control_msgs/FollowJointTrajectoryResult`` error codes (the same in ROS 1 and ROS 2).
- :data:`CONTROLLER_JOINTS`: the controllers' joints, in their order (``ur3_controllers.yaml``); a goal may list
  them in any order. The ROS 1 driver's ``/joint_states`` lists them alphabetically (:data:`ROS1_JOINT_STATE_ORDER`);
  no order is guaranteed on ROS 2: clients index joint states by name.
- IO: the ``ur_msgs/SetIO`` functions, the pin mapping of ``FUN_SET_DIGITAL_OUT`` (0-7 standard, 8-15 configurable,
  16-17 tool outputs) and the ``io_states`` layout (18 digital in/out, 2 analog in/out, ``pin`` = index).
- :data:`ROS1`: the ROS 1 driver's topic, service and action names (``ur_robot_driver``'s defaults).
- :data:`MSG_TEXTS`: the official ``control_msgs`` and ``ur_msgs`` texts, vendored once for both bindings
  (:func:`msg_text`; provenance, git blob ids and which ROS reads which file in ``msg_texts/README.md``).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum
from pathlib import Path

from ur3hanoi.robot.urdf import JOINT_NAMES

CONTROLLER_JOINTS: tuple[str, ...] = JOINT_NAMES
"""The trajectory controllers' joints, in their order (the URDF's; ``ur3_controllers.yaml``)."""
ROS1_JOINT_STATE_ORDER: tuple[str, ...] = tuple(sorted(JOINT_NAMES))
"""The order of the ROS 1 driver's ``/joint_states``: alphabetical (URD1 issues #619, #173)."""


class ErrorCode(IntEnum):
    """``FollowJointTrajectoryResult.error_code``."""

    SUCCESSFUL = 0
    INVALID_GOAL = -1
    INVALID_JOINTS = -2
    OLD_HEADER_TIMESTAMP = -3
    PATH_TOLERANCE_VIOLATED = -4
    GOAL_TOLERANCE_VIOLATED = -5


def code_name(code: int) -> str:
    """``PATH_TOLERANCE_VIOLATED (-4)``; an unknown code as ``error code 7``."""
    try:
        return f"{ErrorCode(code).name} ({code})"
    except ValueError:
        return f"error code {code}"


# ------------------------------------------------------------------------------------------------------ IO
FUN_SET_DIGITAL_OUT = 1
FUN_SET_FLAG = 2
FUN_SET_ANALOG_OUT = 3
FUN_SET_TOOL_VOLTAGE = 4
"""``ur_msgs/SetIO`` functions; the drivers serve 1, 3 and 4 (``FUN_SET_FLAG`` answers ``success = false``)."""

N_DIGITAL = 18
"""Digital inputs and outputs in ``io_states``: 8 standard, 8 configurable, 2 tool; ``pin`` = the index."""
N_ANALOG = 2
"""Standard analog inputs and outputs in ``io_states``."""
STANDARD_DO = range(0, 8)
CONFIGURABLE_DO = range(8, 16)
TOOL_DO = range(16, 18)
"""``set_io`` pins of ``FUN_SET_DIGITAL_OUT``: standard, configurable (pin - 8) and tool (pin - 16) outputs."""
TOOL_VOLTAGES = (0.0, 12.0, 24.0)
"""``FUN_SET_TOOL_VOLTAGE`` states [V]."""
ANALOG_CURRENT = 0
ANALOG_VOLTAGE = 1
"""``ur_msgs/Analog.domain`` (ur_msgs >= 1.3.2; before, VOLTAGE was 0)."""


# ---------------------------------------------------------------------------------------------------- names
@dataclass(frozen=True)
class DriverNames:
    """A driver's ROS names (absolute)."""

    joint_states: str
    follow_joint_trajectory: str
    set_io: str
    io_states: str
    speed_scaling: str
    program_running: str = ""
    """The latched ``std_msgs/Bool``: whether the External Control program runs (ROS 2: transient local)."""


ROS1 = DriverNames(
    joint_states="/joint_states",
    follow_joint_trajectory="/scaled_pos_joint_traj_controller/follow_joint_trajectory",
    set_io="/ur_hardware_interface/set_io",
    io_states="/ur_hardware_interface/io_states",
    speed_scaling="/speed_scaling_factor",
    program_running="/ur_hardware_interface/robot_program_running",
)
"""The ROS 1 ``ur_robot_driver`` (``ur3_bringup.launch``): ``speed_scaling`` is a ``std_msgs/Float64`` fraction."""


# -------------------------------------------------------------------------------------------- message texts
MSG_TEXTS = Path(__file__).resolve().parent / "msg_texts"
"""The official message texts, byte for byte as upstream has them, one file per distinct text: ``control_msgs/`` and
``ur_msgs/``. A suffix names a version-specific text (``-ros1``: ROS 1 Noetic; ``-jazzy``, ``-kilted``: the two ROS 2
layouts of ``FollowJointTrajectory``; ``-1.3``: ur_msgs 1.3.x); no suffix: the text ROS 1 and ROS 2 share, or ROS 2's.
The ROS 1 binding generates its classes from them with genpy (:mod:`ur3hanoi.interface.ros1.driver_msgs`), the
ROS 2 environment builds them with rosidl (:mod:`ur3hanoi.interface.ros2.rclpy_build`)."""


def msg_text(package: str, file: str) -> str:
    """The vendored text of ``package/file`` (``msg_text("ur_msgs", "SetIO-1.3.srv")``)."""
    return (MSG_TEXTS / package / file).read_text(encoding="utf-8")
