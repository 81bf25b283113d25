"""Run the lab in MuJoCo: the UR3 model, the task scene, suction with feedback, plan execution with the lab's
fault handling, and rendering.

Modules, in order of dependency (each imports only the ones above it):

- :mod:`~ur3hanoi.sim.model`: ``robots/universal_robots_ur3/ur3.xml`` derived from example-robot-data's
  ``ur3_robot.urdf`` (:func:`derive_ur3_mjcf`, :func:`write_ur3_files`; ``python -m ur3hanoi.sim`` regenerates
  it), the joint drives (:class:`JointDrive`, :data:`DRIVES`).
- :mod:`~ur3hanoi.sim.scene`: the station's task scene built with :class:`mujoco.MjSpec` (:class:`SceneConfig`,
  :func:`build_task_spec`, :func:`build_task_scene`, :class:`TaskScene`), the blocks' start slots and names.
- :mod:`~ur3hanoi.sim.suction`: the emulated vacuum gripper and its ``gripper_input`` feedback
  (:class:`SuctionConfig`, :class:`SuctionCup`, :class:`GripperInput`).
- :mod:`~ur3hanoi.sim.config`: the settings of a simulated lab, one type for both drivers (:class:`SimConfig`).
- :mod:`~ur3hanoi.sim.servo`: the one servo law of the simulated UR controller (interpolation, velocity and
  acceleration feed-forward), through which both drivers step the scene (:class:`~ur3hanoi.sim.servo.JointServo`).
- :mod:`~ur3hanoi.sim.halt`: the motion of a halt (:class:`HaltProfile`, :data:`DEFAULT_HALT_PROFILE`: Ruckig).
- :mod:`~ur3hanoi.sim.result`: what a run reports (:class:`SimResult`, :class:`FeedbackEvent`,
  :class:`FinalBlock`, :class:`DisplacedBlock`, :class:`JointTrace`).
- :mod:`~ur3hanoi.sim.diagnosis`: what a halt says happened: the block actually missing, a grasp the cup did not
  reach, blocks knocked out of place after the halt (:class:`DisplacedBlock`).
- :mod:`~ur3hanoi.sim.verify`: where every block is, whether the arm is home, ``solve``'s final check.
- :mod:`~ur3hanoi.sim.suction_check`: the lab program's suction check while a plan streams.
- :mod:`~ur3hanoi.sim.executor`: ``solve``'s driver: :func:`run_plan` streams a :class:`ur3hanoi.plan.Plan`, checks
  the suction like the lab program, halts on a fault (raising :class:`ur3hanoi.errors.SuctionFaultError` with the
  result) and verifies the final block positions (:class:`Faults`).
- :mod:`~ur3hanoi.sim.task_world`: what the ROS servers drive one control period at a time: the scene, servo, suction
  and blocks of a station (:class:`~ur3hanoi.sim.task_world.TaskWorld`, :class:`WorldEvent`).
- :mod:`~ur3hanoi.sim.world`: the course interface's world: :class:`MoveJWorld` runs ``movej`` commands.
- :mod:`~ur3hanoi.sim.servo_world`: the official UR driver's world: :class:`ServoWorld`, the robot under a streaming
  trajectory controller (joint limits, its own speed scaling times the slider, an arm that can be held).
- :mod:`~ur3hanoi.sim.render`: offscreen frames/video and the interactive viewer (:class:`CameraConfig`,
  :class:`OffscreenRecorder`, :data:`VIDEO_FORMATS`, :func:`check_video_path`, :class:`ViewerSink`), with the
  OpenGL platform chosen before MuJoCo is imported (:mod:`ur3hanoi.opengl`; :func:`display_available` is its).

Frames: MuJoCo's world is the station's world. The URDF root ``base_link`` is placed at
``T_world_base * Rz(pi)`` so that MuJoCo's ``suction`` site equals ``T_world_base * Ur3Model.fk(q, "tcp")``.
Joint values are the controller/DH convention (they equal the URDF's, see :mod:`ur3hanoi.robot.model`).

Numbering: internally 0-based (towers, heights, blocks, moves); messages and JSON are 1-based like the lab.
"""

from ur3hanoi.opengl import display_available
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.executor import Faults, FrameSink, ProgressFn, run_plan
from ur3hanoi.sim.halt import DEFAULT_HALT_PROFILE, HaltProfile
from ur3hanoi.sim.model import (
    DRIVES,
    ROBOT_DIR,
    SCENE_XML,
    UR3_XML,
    JointDrive,
    derive_ur3_mjcf,
    ur3_mesh_sources,
    write_ur3_files,
)
from ur3hanoi.sim.render import (
    VIDEO_FORMATS,
    CameraConfig,
    OffscreenRecorder,
    VideoFormat,
    ViewerSink,
    check_video_path,
)
from ur3hanoi.sim.result import DisplacedBlock, FeedbackEvent, FinalBlock, JointTrace, SimResult
from ur3hanoi.sim.scene import (
    SceneConfig,
    TaskScene,
    block_name,
    build_task_scene,
    build_task_spec,
    slot_centers,
    slot_of,
    start_slots,
    warning_counts,
)
from ur3hanoi.sim.servo_world import ServoWorld
from ur3hanoi.sim.suction import GripperInput, SuctionConfig, SuctionCup
from ur3hanoi.sim.task_world import TaskWorld
from ur3hanoi.sim.world import MoveJWorld, WorldEvent

__all__ = [
    "DEFAULT_HALT_PROFILE",
    "DRIVES",
    "ROBOT_DIR",
    "SCENE_XML",
    "UR3_XML",
    "VIDEO_FORMATS",
    "CameraConfig",
    "DisplacedBlock",
    "Faults",
    "FeedbackEvent",
    "FinalBlock",
    "FrameSink",
    "GripperInput",
    "HaltProfile",
    "JointDrive",
    "JointTrace",
    "MoveJWorld",
    "OffscreenRecorder",
    "ProgressFn",
    "SceneConfig",
    "ServoWorld",
    "SimConfig",
    "SimResult",
    "SuctionConfig",
    "SuctionCup",
    "TaskScene",
    "TaskWorld",
    "VideoFormat",
    "ViewerSink",
    "WorldEvent",
    "block_name",
    "build_task_scene",
    "build_task_spec",
    "check_video_path",
    "derive_ur3_mjcf",
    "display_available",
    "run_plan",
    "slot_centers",
    "slot_of",
    "start_slots",
    "ur3_mesh_sources",
    "warning_counts",
    "write_ur3_files",
]
