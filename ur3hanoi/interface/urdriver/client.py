"""What a client of the official UR driver needs from its middleware: :class:`DriverTransport`.

A binding (ROS 1: :class:`ur3hanoi.interface.ros1.ur_client.RosDriverTransport`; ROS 2: the rclpy one) connects to
the driver, keeps the latest joint states (by joint name, into
:data:`~ur3hanoi.interface.urdriver.facts.CONTROLLER_JOINTS` order), ``io_states`` and speed scaling (as a fraction),
sends ``FollowJointTrajectory`` goals and calls ``set_io``; it adds every joint state to its
:class:`~ur3hanoi.interface.urdriver.joint_record.JointRecord`.
Everything else -- the plan as goals, the suction checks, halts, timeouts and errors -- is the middleware-neutral
solve (:func:`ur3hanoi.interface.urdriver.solve.run_driver_solve`), the same on ROS 1 and ROS 2.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Protocol

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import DriverError
from ur3hanoi.interface.urdriver.facts import code_name
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal
from ur3hanoi.interface.urdriver.io import IoStates
from ur3hanoi.interface.urdriver.joint_record import JointRecord

GoalStatus = Literal["succeeded", "aborted", "rejected", "canceled", "preempted", "lost"]


@dataclass(frozen=True)
class GoalResult:
    """How a goal ended, as the client saw it: ``code`` None when the driver sent none (a ROS 2 rejection, a cancel
    without a result)."""

    status: GoalStatus
    code: int | None = None
    error_string: str = ""

    def describe(self) -> str:
        """``aborted: PATH_TOLERANCE_VIOLATED (-4) "shoulder_pan_joint path error 0.2"``; a rejection without a code
        (ROS 2 rejects at ``send_goal``) says where to look."""
        if self.status == "rejected" and self.code is None:
            return "rejected at send_goal (the ROS 2 driver gives no code: its log says why)"
        if self.status == "preempted":
            return "preempted (by another client's goal, or the controller stopped: does the robot program run on " \
                   "the pendant?)"
        text = self.status if self.code is None else f"{self.status}: {code_name(self.code)}"
        return text + (f' "{self.error_string}"' if self.error_string else ' (no error string)' if self.code else "")


@dataclass(frozen=True)
class DriverState:
    """The latest of what the driver publishes: joint positions [rad] (controller order; None before the first
    message) with their time of arrival (the transport's :meth:`DriverTransport.now`), ``io_states``, speed scaling
    as a fraction, whether the External Control program runs (``robot_program_running``; None: not heard yet)."""

    q: FloatArray | None = None
    t_q: float = 0.0
    io: IoStates | None = None
    speed_scaling: float | None = None
    program_running: bool | None = None


class GoalHandle(Protocol):
    """A sent goal."""

    def done(self) -> bool:
        """True once the goal is rejected or has a result."""

    def result(self) -> GoalResult:
        """How it ended (call once :meth:`done`)."""

    def cancel(self) -> None:
        """Ask the driver to cancel it (does not wait)."""


class DriverTransport(Protocol):
    """A binding's connection to the driver (see the module docstring)."""

    where: str
    """Where the driver is, for messages (the ROS master URI, the ROS 2 domain)."""
    record: JointRecord
    """Every joint state received (with :meth:`now` at its arrival) while the solve records: the transport adds each
    message, the solve starts and stops it (and measures the path from it afterwards)."""

    def connect(self) -> None:
        """Wait for the driver's joint states, ``io_states``, action server and ``set_io`` service.

        Raises:
            DriverError: not all within the binding's wait: one line naming what is missing.
        """

    def now(self) -> float:
        """The client's clock [s]: ``time.monotonic()`` on a real transport; a simulated station's world time on
        the CPU-clock loopback (:mod:`ur3hanoi.interface.urdriver.loopback`)."""

    def latest(self) -> DriverState:
        """The latest joint states, ``io_states`` and speed scaling."""

    def send_goal(self, goal: TrajectoryGoal) -> GoalHandle:
        """Send ``goal`` to the scaled trajectory controller (does not wait)."""

    def set_io(self, fun: int, pin: int, state: float) -> bool:
        """Call ``set_io`` and return its ``success``."""

    def wait(self, timeout_s: float) -> None:
        """Return when something new arrived (a joint state, ``io_states``, a goal's result) or after
        ``timeout_s`` [s]."""

    def close(self) -> None:
        """Disconnect (idempotent)."""


class DriverGoalError(DriverError):
    """The driver's controller rejected or aborted a goal; ``result`` says how (code and error string)."""

    def __init__(self, message: str, result: GoalResult) -> None:
        super().__init__(message)
        self.result = result
