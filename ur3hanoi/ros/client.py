"""A rospy client of the course's interface: ``ur3/command`` out, ``ur3/position`` and ``ur3/gripper_input`` in.

:class:`RosArm` implements :class:`ur3hanoi.ros.solve.Arm` the way the lab's ``move_arm``/``gripper`` do, with
the gaps closed: it waits for the driver before the first command (a rospy publisher drops messages until a
subscriber is connected), a move returns once every joint is within 0.0005 rad of the destination and re-publishes
the command every 5 s like the lab's, but gives up with an error after ``move_timeout_s`` instead of hanging; the
suction is switched by re-sending the last *commanded* destination (the lab sends the measured position, which
makes a controller move by its tracking error).
"""

from __future__ import annotations

import math
import os
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.ros.errors import RosError


@dataclass(frozen=True)
class ArmConfig:
    """How the client commands and waits.

    Attributes:
        v, a: joint speed [rad/s] and acceleration [rad/s^2] sent with every command (the lab's starter: 4.0 and
            4.0; the controller caps them at the joint limits).
        tolerance_rad: a move is done when every joint is within this angle [rad] of its destination (the lab's).
        republish_s: re-publish a command not yet reached after this long [s] (the lab's 5 s).
        poll_s: period [s] of the waiting loops.
        move_timeout_s: give up on a move after this long [s].
        connect_timeout_s: wait this long [s] for the driver's topics.
        position_timeout_s: a move fails when no ``ur3/position`` arrived for this long [s] (the driver publishes
            it every control cycle: silence means it stopped, not that the arm is slow).
    """

    v: float = 4.0
    a: float = 4.0
    tolerance_rad: float = 5e-4
    republish_s: float = 5.0
    poll_s: float = 0.004
    move_timeout_s: float = 60.0
    connect_timeout_s: float = 15.0
    position_timeout_s: float = 2.0


class RosArm:
    """The robot as seen through the course's ROS topics (see the module docstring). Call :meth:`connect` first.

    Args:
        config: command speed, tolerances and timeouts.
        master_uri: ROS master (None: ``ROS_MASTER_URI``, else http://localhost:11311).
        log: where re-publish notices go.
    """

    def __init__(self, config: ArmConfig | None = None, master_uri: str | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        from ur3hanoi.ros.master import master_uri_from_env

        self.config = config if config is not None else ArmConfig()
        self.master_uri = master_uri or master_uri_from_env()
        self.log = log if log is not None else (lambda s: print(s, file=sys.stderr))
        self._q: FloatArray | None = None
        self._t_position = -math.inf  # time.monotonic() of the last ur3/position message
        self._digin: int | None = None
        self._ain0 = float("nan")
        self._destination: FloatArray | None = None
        self._io = False
        self._rospy: Any = None
        self._msgs: Any = None
        self._pub: Any = None
        self.commands_sent = 0

    # --------------------------------------------------------------------------------------------- callbacks
    def _on_position(self, msg: Any) -> None:
        self._q = np.array(msg.position, dtype=float)
        self._t_position = time.monotonic()

    def _on_gripper(self, msg: Any) -> None:
        self._ain0 = float(msg.AIN0)
        self._digin = int(msg.DIGIN)

    # --------------------------------------------------------------------------------------------- connection
    def connect(self) -> None:
        """Register with the master and wait for the driver's position, feedback and command subscription.

        Raises:
            RosError: no master, or the driver's topics do not appear within ``connect_timeout_s``.
        """
        from ur3hanoi.ros.env import import_rospy
        from ur3hanoi.ros.master import MasterUri, master_answers
        from ur3hanoi.ros.msgs import load_messages

        MasterUri.parse(self.master_uri)
        if not master_answers(self.master_uri, timeout=2.0):
            raise RosError(f"no ROS master answers at {self.master_uri}: start `ur3hanoi ros-station` (it starts one) "
                           "or the course's ur3_driver, or set ROS_MASTER_URI")
        self._msgs = msgs = load_messages()
        rospy = self._rospy = import_rospy()
        os.environ["ROS_MASTER_URI"] = self.master_uri
        rospy.init_node("ur3hanoi_solve", anonymous=True, argv=[sys.argv[0]], disable_signals=True)
        self._pub = rospy.Publisher("/ur3/command", msgs.command, queue_size=10)
        rospy.Subscriber("/ur3/position", msgs.position, self._on_position, tcp_nodelay=True)
        rospy.Subscriber("/ur3/gripper_input", msgs.gripper_input, self._on_gripper, tcp_nodelay=True)
        ok = self.wait_until(lambda: self._q is not None and self._digin is not None
                             and self._pub.get_num_connections() > 0, self.config.connect_timeout_s)
        if not ok:
            missing = [name for name, seen in (("ur3/position", self._q is not None),
                                               ("ur3/gripper_input", self._digin is not None),
                                               ("a ur3/command subscriber", self._pub.get_num_connections() > 0))
                       if not seen]
            raise RosError(f"no {', '.join(missing)} within {self.config.connect_timeout_s:g} s on "
                           f"{self.master_uri}: is ros-station or the course's ur3_driver running?")
        self._destination = self.q

    def close(self) -> None:
        """Unregister the node."""
        if self._rospy is not None:
            self._rospy.signal_shutdown("ur3hanoi ros-solve done")

    # ---------------------------------------------------------------------------------------------- state
    @property
    def q(self) -> FloatArray:
        """The last ``ur3/position`` [rad]."""
        if self._q is None:
            raise RosError("no ur3/position received yet: call connect() first")
        return self._q.copy()

    def held(self) -> bool:
        return bool((self._digin or 0) & 1)

    def feedback_text(self) -> str:
        return f"DIGIN={self._digin}, AIN0={self._ain0:.2f} V"

    # ---------------------------------------------------------------------------------------------- motion
    def _publish(self, destination: FloatArray, io_0: bool) -> Any:
        msg = self._msgs.command(destination=[float(x) for x in destination], v=self.config.v, a=self.config.a,
                                 io_0=io_0)
        self._pub.publish(msg)
        self.commands_sent += 1
        return msg

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while True:
            if predicate():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(self.config.poll_s)

    def move(self, q: FloatArray, watch: Callable[[], None] | None = None) -> None:
        """Command ``q`` [rad] (with the current suction state) and wait until every joint is within tolerance.

        Raises:
            RosError: not reached within ``move_timeout_s`` (re-published every ``republish_s``).
        """
        cfg = self.config
        goal = np.array(q, dtype=float)
        msg = self._publish(goal, self._io)
        self._destination = goal
        t0 = last = time.monotonic()
        while True:
            if watch is not None:
                watch()
            if self._q is not None and float(np.max(np.abs(self._q - goal))) < cfg.tolerance_rad:
                return
            now = time.monotonic()
            silent = now - max(self._t_position, t0)
            if silent > cfg.position_timeout_s:
                raise RosError(f"position updates stopped: no message on /ur3/position for {silent:.1f} s (the "
                               "driver publishes it every cycle); is the driver still running?")
            if now - t0 > cfg.move_timeout_s:
                err = float(np.max(np.abs(self.q - goal)))
                raise RosError(f"the arm did not reach {np.round(goal, 4).tolist()} within {cfg.move_timeout_s:g} s "
                               f"(still {err:.4f} rad away): expected every joint within {cfg.tolerance_rad} rad")
            if now - last >= cfg.republish_s:
                self._pub.publish(msg)
                self.log("ur3hanoi: re-published the command (destination not reached yet)")
                last = now
            time.sleep(cfg.poll_s)

    def suction(self, on: bool) -> None:
        """Re-send the last commanded destination with ``io_0 = on`` (no motion) and wait until there."""
        self._io = bool(on)
        self.move(self._destination if self._destination is not None else self.q)
