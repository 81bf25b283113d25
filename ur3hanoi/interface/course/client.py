"""The client side of a remote station, whatever the middleware: command a joint move, wait until the arm is
there, read the suction feedback.

:class:`TopicArm` implements :class:`ur3hanoi.interface.course.solve.Arm` over three topics (a command out, the position
and the gripper input in) the way the lab's ``move_arm``/``gripper`` do, with the gaps closed: a move returns once
every joint is within ``tolerance_rad`` of the destination and re-publishes the command every ``republish_s`` like
the lab's, but gives up with an error after ``move_timeout_s`` instead of hanging, and at once when the position
stops arriving (``position_timeout_s``: the driver publishes it every control cycle); the suction is switched by
re-sending the last *commanded* destination (the lab sends the measured position, which makes a controller move
by its tracking error). A binding (:class:`ur3hanoi.interface.ros1.client.RosArm` on rospy,
:class:`ur3hanoi.interface.ros2.client.Ros2Arm` on Cyclone DDS) connects, sends and receives; it calls
:meth:`TopicArm._position` and :meth:`TopicArm._feedback` with what arrives.

For ``ur3hanoi teach`` (:mod:`ur3hanoi.teach`) the arm also keeps the positions of the last
:data:`HISTORY_S` seconds with their arrival times (:meth:`TopicArm.samples`: is the arm still?), sends a move
without waiting at a speed of the caller's (:meth:`TopicArm.send`), and names a position message that is not six
finite angles (:attr:`TopicArm.malformed`) instead of taking it.
"""

from __future__ import annotations

import math
import sys
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import DriverError

HISTORY_S = 2.0
"""[s] how long the arm keeps the positions that arrived (:meth:`TopicArm.samples`)."""
_HISTORY_MAX = 4000  # positions kept at most: 2 s at 2 kHz, more than any driver publishes


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
        position_timeout_s: a move fails when no position message arrived for this long [s] (the driver publishes
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


@dataclass(frozen=True)
class Topics:
    """The names a binding's messages mention: the three topics and the feedback's two fields."""

    command: str
    position: str
    gripper: str
    digital: str = "DIGIN"
    analog: str = "AIN0"


class TopicArm:
    """The robot as seen through a command, a position and a gripper-input topic (see the module docstring).

    Args:
        config: command speed, tolerances and timeouts.
        topics: the binding's topic and field names (for messages).
        log: where re-publish notices go (default: stderr).
    """

    def __init__(self, config: ArmConfig, topics: Topics, log: Callable[[str], None] | None = None) -> None:
        self.config = config
        self.topics = topics
        self.log = log if log is not None else (lambda s: print(s, file=sys.stderr))
        self._q: FloatArray | None = None  # controller convention
        self._t_position = -math.inf  # time.monotonic() of the last position message
        self._history: deque[tuple[float, FloatArray]] = deque(maxlen=_HISTORY_MAX)
        self.malformed = ""
        """What was wrong with the last position message that was not six finite angles ("" if none was)."""
        self._digin: int | None = None
        self._ain0 = float("nan")
        self._destination: FloatArray | None = None
        self._io = False
        self.commands_sent = 0

    # ------------------------------------------------------------------------------------ the binding's part
    def _poll(self) -> None:
        """Take what arrived (a binding whose callbacks run in their own threads has nothing to do)."""

    def _publish(self, destination: FloatArray, io_0: bool, v: float, a: float) -> Any:
        """Send a command (``destination`` [rad, controller convention], joint speed ``v`` [rad/s] and acceleration
        ``a`` [rad/s^2]); returns the message for re-publishing."""
        raise NotImplementedError

    def _republish(self, msg: Any) -> None:
        """Send ``msg`` again."""
        raise NotImplementedError

    def _subscribed(self) -> bool:
        """The driver subscribes to the command topic (a command sent before would be lost)."""
        raise NotImplementedError

    def _position(self, q: FloatArray) -> None:
        """A position message arrived: ``q`` [rad, controller convention]; one that is not six finite angles is
        named in :attr:`malformed` and not taken."""
        if q.shape != (6,) or not bool(np.all(np.isfinite(q))):
            self.malformed = (f"{q.size} joint values (expected 6)" if q.shape != (6,) else
                              f"a non-finite joint value ({', '.join(f'{x:g}' for x in q.tolist())})")
            return
        now = time.monotonic()
        self._q = q
        self._t_position = now
        self._history.append((now, q))
        while self._history[0][0] < now - HISTORY_S:
            self._history.popleft()

    def _feedback(self, digin: int, ain0: float) -> None:
        """A gripper-input message arrived: the digital inputs and the analog input 0 [V]."""
        self._digin, self._ain0 = digin, ain0

    def _await_driver(self, where: str, driver: str) -> None:
        """Wait for the driver's position, feedback and command subscription, then take the position as the last
        destination.

        Raises:
            DriverError: naming what did not appear within ``connect_timeout_s`` on ``where`` and the ``driver``
                that should be running.
        """
        ok = self.wait_until(lambda: bool(self.malformed) or (self._q is not None and self._digin is not None
                                                                and self._subscribed()),
                             self.config.connect_timeout_s)
        if self.malformed and self._q is None:
            raise DriverError(f"the driver on {where} publishes {self.malformed} on {self.topics.position}: is it a UR "
                           f"driver ({driver})?")
        if not ok:
            t = self.topics
            missing = [name for name, seen in ((t.position, self._q is not None), (t.gripper, self._digin is not None),
                                               (f"a {t.command} subscriber", self._subscribed())) if not seen]
            raise DriverError(f"no {', '.join(missing)} within {self.config.connect_timeout_s:g} s on {where}: is "
                           f"{driver} running?")
        self._destination = self.q

    # ---------------------------------------------------------------------------------------------- state
    @property
    def q(self) -> FloatArray:
        """The last position [rad, controller convention]."""
        self._poll()
        if self._q is None:
            raise DriverError(f"no {self.topics.position} received yet: call connect() first")
        return self._q.copy()

    def held(self) -> bool:
        """The vacuum switch: ``DIGIN`` bit 0."""
        self._poll()
        return bool((self._digin or 0) & 1)

    def samples(self, window_s: float) -> list[tuple[float, FloatArray]]:
        """The positions that arrived in the last ``window_s`` seconds (at most :data:`HISTORY_S`), oldest first:
        ``(time.monotonic() of arrival, q [rad, controller convention])``."""
        self._poll()
        since = time.monotonic() - window_s
        return [(t, q) for t, q in list(self._history) if t >= since]

    def send(self, q: FloatArray, v: float, a: float) -> None:
        """Command a joint move to ``q`` [rad] at joint speed ``v`` [rad/s] and acceleration ``a`` [rad/s^2] (the
        current suction state), without waiting."""
        goal = np.array(q, dtype=float)
        self._publish(goal, self._io, v, a)
        self.commands_sent += 1
        self._destination = goal

    def feedback_text(self) -> str:
        return f"{self.topics.digital}={self._digin}, {self.topics.analog}={self._ain0:.2f} V"

    # ---------------------------------------------------------------------------------------------- motion
    def wait_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        deadline = time.monotonic() + timeout_s
        while True:
            self._poll()
            if predicate():
                return True
            if time.monotonic() >= deadline:
                return False
            time.sleep(self.config.poll_s)

    def move(self, q: FloatArray, watch: Callable[[], None] | None = None) -> None:
        """Command ``q`` [rad] (with the current suction state) and wait until every joint is within tolerance.

        Raises:
            DriverError: not reached within ``move_timeout_s`` (re-published every ``republish_s``), or no position
                message for ``position_timeout_s``.
        """
        cfg = self.config
        goal = np.array(q, dtype=float)
        msg = self._publish(goal, self._io, cfg.v, cfg.a)
        self.commands_sent += 1
        self._destination = goal
        t0 = last = time.monotonic()
        while True:
            self._poll()
            if watch is not None:
                watch()
            if self._q is not None and float(np.max(np.abs(self._q - goal))) < cfg.tolerance_rad:
                return
            now = time.monotonic()
            silent = now - max(self._t_position, t0)
            if silent > cfg.position_timeout_s:
                raise DriverError(f"position updates stopped: no message on /{self.topics.position} for {silent:.1f} s "
                               "(the driver publishes it every cycle); is the driver still running?")
            if now - t0 > cfg.move_timeout_s:
                err = float(np.max(np.abs(self.q - goal)))
                raise DriverError(f"the arm did not reach {np.round(goal, 4).tolist()} within {cfg.move_timeout_s:g} s "
                               f"(still {err:.4f} rad away): expected every joint within {cfg.tolerance_rad} rad")
            if now - last >= cfg.republish_s:
                self._republish(msg)
                self.log("ur3hanoi: re-published the command (destination not reached yet)")
                last = now
            time.sleep(cfg.poll_s)

    def suction(self, on: bool) -> None:
        """Re-send the last commanded destination with ``io_0 = on`` (no motion) and wait until there."""
        self._io = bool(on)
        self.move(self._destination if self._destination is not None else self.q)
