"""The station's controller logic: accept or refuse commands, execute them in order, measure how the arm settles.

:class:`StationDriver` sits between the ROS callbacks and :class:`~ur3hanoi.ros.world.StationWorld`. Accepted
commands wait in a FIFO and each starts when the previous motion's profile has ended (a controller's motion
queue); the lab's ``move_arm`` re-publishes its command every 5 s while waiting, which then costs a zero-length
move, never a jump. Every executed command is recorded with its duration, the time the arm needed to come within
the settle tolerance after the profile ended, and the error it rested at, so the report shows whether the lab's
0.0005 rad wait would return.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ur3hanoi.ros.command import MoveCommand, parse_command
from ur3hanoi.ros.errors import CommandError
from ur3hanoi.ros.world import StationWorld


@dataclass
class ExecutedMove:
    """One executed command and how it went. Times [s] are world times; errors [rad] the largest joint error."""

    command: MoveCommand
    t_start: float
    duration_s: float
    lead_velocity: float  # [rad/s] peak speed of the fastest joint (after the caps)
    lead_acceleration: float  # [rad/s^2]
    settle_s: float | None = None  # from the profile's end to the first period within tolerance (None: not yet)
    rest_s: float = 0.0  # how long the arm then rested within tolerance before the next command (or now)
    rest_error_rad: float | None = None  # error when the next command started (or now)
    rest_max_error_rad: float | None = None  # largest error at rest after settling

    def as_dict(self) -> dict[str, Any]:
        def r(x: float | None, n: int = 6) -> float | None:
            return None if x is None else round(x, n)

        return {**self.command.as_dict(), "t_start": round(self.t_start, 4), "duration_s": round(self.duration_s, 4),
                "lead_velocity": round(self.lead_velocity, 4), "lead_acceleration": round(self.lead_acceleration, 4),
                "settle_s": r(self.settle_s, 4), "rest_s": round(self.rest_s, 4),
                "rest_error_rad": r(self.rest_error_rad, 9),
                "rest_max_error_rad": r(self.rest_max_error_rad, 9)}


@dataclass(frozen=True)
class Rejection:
    """A refused command: world time [s] and the reason (one line)."""

    t: float
    reason: str

    def as_dict(self) -> dict[str, Any]:
        return {"t": round(self.t, 4), "reason": self.reason}


class StationDriver:
    """Command FIFO and records over a :class:`StationWorld` (see the module docstring).

    Args:
        world: the simulated station.
        max_queue: commands waiting beyond this many are refused (a runaway publisher must not queue minutes).
        min_rest_s: the summary's rest error counts only rests at least this long [s].
    """

    def __init__(self, world: StationWorld, max_queue: int = 100, min_rest_s: float = 0.2) -> None:
        self.world = world
        self.max_queue = max_queue
        self.min_rest_s = min_rest_s
        self.queue: deque[MoveCommand] = deque()
        self.executed: list[ExecutedMove] = []
        self.rejected: list[Rejection] = []
        self._current: ExecutedMove | None = None
        self._profile_end: float | None = None

    def submit(self, destination: Sequence[float], v: object, a: object, io_0: object) -> MoveCommand:
        """Queue a ``ur3/command``.

        Raises:
            CommandError: the command is refused (recorded in :attr:`rejected`); nothing moves.
        """
        try:
            command = parse_command(destination, v, a, io_0, self.world.station.limits)
            if len(self.queue) >= self.max_queue:
                raise CommandError(f"{len(self.queue)} commands are already waiting: expected at most "
                                   f"{self.max_queue} queued commands")
        except CommandError as exc:
            self.rejected.append(Rejection(self.world.time, str(exc)))
            raise
        self.queue.append(command)
        return command

    @property
    def ready(self) -> bool:
        """``isReady``: nothing queued, no profile running, every joint within tolerance of the destination."""
        return not self.queue and self.world.settled

    def _close_rest(self) -> None:
        if self._current is not None and self._current.settle_s is not None:
            self._current.rest_error_rad = self.world.error_to_target()

    def cycle(self) -> None:
        """One control period: start the next queued command when the arm is free, step the world, measure."""
        w = self.world
        if not w.moving and self.queue:
            self._close_rest()
            command = self.queue.popleft()
            motion = w.begin(command)
            v, acc = motion.peak_velocity, motion.peak_acceleration
            self._current = ExecutedMove(command, w.time, motion.duration, float(v.max()), float(acc.max()))
            self.executed.append(self._current)
            self._profile_end = None if w.moving else w.time
        w.step()
        cur = self._current
        if cur is None:
            return
        if self._profile_end is None and not w.moving:
            self._profile_end = w.time
        if self._profile_end is not None:
            err = w.error_to_target()
            if cur.settle_s is None and err <= w.config.settle_tolerance_rad:
                cur.settle_s = max(0.0, w.time - self._profile_end)
            if cur.settle_s is not None:
                cur.rest_max_error_rad = max(err, cur.rest_max_error_rad or 0.0)
                cur.rest_s = w.time - self._profile_end - cur.settle_s

    def summary(self) -> dict[str, Any]:
        """Counts and the worst settle figures of the executed commands."""
        self._close_rest()
        settles = [m.settle_s for m in self.executed if m.settle_s is not None]
        # At rest: the arm stayed at least min_rest_s (clients that move on at once never let it rest).
        rests = [m.rest_error_rad for m in self.executed
                 if m.rest_error_rad is not None and m.rest_s >= self.min_rest_s]
        drifts = [m.rest_max_error_rad for m in self.executed if m.rest_max_error_rad is not None]
        return {
            "executed": len(self.executed),
            "rejected": len(self.rejected),
            "queued": len(self.queue),
            # The next command started before this one came within tolerance (the client moved on early).
            "superseded_before_settling": sum(1 for m in self.executed if m.settle_s is None),
            "max_settle_s": round(max(settles), 4) if settles else None,
            "max_rest_error_rad": max(rests) if rests else None,
            "max_error_after_settling_rad": max(drifts) if drifts else None,
            "settle_tolerance_rad": self.world.config.settle_tolerance_rad,
        }
