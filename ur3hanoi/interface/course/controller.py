"""The station's controller logic: accept or refuse commands, execute them in order, measure how the arm settles.

:class:`Controller` sits between the ROS callbacks and :class:`~ur3hanoi.sim.world.MoveJWorld`. Accepted
commands wait in a FIFO and each starts when the previous motion's profile has ended (a controller's motion
queue); the lab's ``move_arm`` re-publishes its command every 5 s while waiting, which then costs a zero-length
move, never a jump. Every executed command is recorded with its duration, the time the arm needed to come within
the settle tolerance after the profile ended, and the error it rested at, so the report shows whether the lab's
0.0005 rad wait would return.

What cannot wedge the station:

- a command whose ``movej`` would take longer than :data:`MAX_MOVE_S` (planned from where the previous command
  ends) is refused: ``v = a = 1e-9`` would otherwise be a 5e8 s move and the station would never move again. 60 s
  covers every lab move at the slowest speeds course drivers accept (``v = a = 0.1``: a lead joint up to 5.9 rad);
- at most ``max_queue`` (100) accepted commands wait; further ones are refused until the queue drains (a runaway
  publisher must not queue minutes of motion);
- the records are bounded: totals and worst figures over every command, and only the last
  :data:`RECORDS_KEPT` executed and refused commands in full, so memory and the report stay the same size
  however many commands arrive.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ur3hanoi.interface.common.errors import CommandError
from ur3hanoi.interface.course.command import MoveCommand, parse_command
from ur3hanoi.robot.movej import plan_movej
from ur3hanoi.sim.world import MoveJWorld

MAX_MOVE_S = 60.0
"""Longest ``movej`` [s] the station accepts (see the module docstring)."""

RECORDS_KEPT = 100
"""How many executed and how many refused commands the driver keeps in full (the report's lists)."""


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


class Controller:
    """Command FIFO and records over a :class:`~ur3hanoi.sim.world.MoveJWorld` (see the module docstring).

    Args:
        world: the simulated station.
        max_queue: commands waiting beyond this many are refused (a runaway publisher must not queue minutes).
        min_rest_s: the summary's rest error counts only rests at least this long [s].
        max_move_s: commands whose move would take longer [s] are refused.
        records_kept: the last this many executed and refused commands are kept in full.
    """

    def __init__(self, world: MoveJWorld, max_queue: int = 100, min_rest_s: float = 0.2,
                 max_move_s: float = MAX_MOVE_S, records_kept: int = RECORDS_KEPT) -> None:
        self.world = world
        self.max_queue = max_queue
        self.min_rest_s = min_rest_s
        self.max_move_s = max_move_s
        self.queue: deque[MoveCommand] = deque()
        self.executed: deque[ExecutedMove] = deque(maxlen=records_kept)
        self.rejected: deque[Rejection] = deque(maxlen=records_kept)
        self.n_executed = 0
        self.n_rejected = 0
        self._current: ExecutedMove | None = None
        self._profile_end: float | None = None
        # Aggregates over the closed records (every executed command but the current one).
        self._superseded = 0
        self._max_settle: float | None = None
        self._max_rest: float | None = None
        self._max_drift: float | None = None

    def refuse(self, reason: str) -> CommandError:
        """Record a refused command; returns the error to raise."""
        self.n_rejected += 1
        self.rejected.append(Rejection(self.world.time, reason))
        return CommandError(reason)

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
            start = self.queue[-1].destination if self.queue else self.world.target
            lim = self.world.station.limits
            duration = plan_movej(start, command.destination, command.v, command.a, lim.v_max, lim.a_max).duration
            if not duration <= self.max_move_s:
                raise CommandError(f"the move would take {duration:.3g} s at v = {command.v!r} rad/s, a = "
                                   f"{command.a!r} rad/s^2: expected at most {self.max_move_s:g} s (raise v or a)")
        except CommandError as exc:
            raise self.refuse(str(exc)) from None
        self.queue.append(command)
        return command

    @property
    def ready(self) -> bool:
        """``isReady``: nothing queued, no profile running, every joint within tolerance of the destination."""
        return not self.queue and self.world.settled

    def _close_rest(self) -> None:
        if self._current is not None and self._current.settle_s is not None:
            self._current.rest_error_rad = self.world.error_to_target()

    def _fold(self, m: ExecutedMove) -> None:
        """Add a closed record to the aggregates."""
        if m.settle_s is None:
            self._superseded += 1
        else:
            self._max_settle = _max(self._max_settle, m.settle_s)
        if m.rest_error_rad is not None and m.rest_s >= self.min_rest_s:
            self._max_rest = _max(self._max_rest, m.rest_error_rad)
        if m.rest_max_error_rad is not None:
            self._max_drift = _max(self._max_drift, m.rest_max_error_rad)

    def cycle(self) -> None:
        """One control period: start the next queued command when the arm is free, step the world, measure."""
        w = self.world
        if not w.moving and self.queue:
            self._close_rest()
            if self._current is not None:
                self._fold(self._current)
            command = self.queue.popleft()
            motion = w.begin(command.destination, command.v, command.a, command.io_0)
            v, acc = motion.peak_velocity, motion.peak_acceleration
            self._current = ExecutedMove(command, w.time, motion.duration, float(v.max()), float(acc.max()))
            self.executed.append(self._current)
            self.n_executed += 1
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
        """Counts and the worst settle figures over every executed command (not only the kept records)."""
        self._close_rest()
        superseded, settle, rest, drift = self._superseded, self._max_settle, self._max_rest, self._max_drift
        m = self._current
        if m is not None:  # the current command, not folded yet
            superseded += m.settle_s is None
            settle = _max(settle, m.settle_s)
            if m.rest_error_rad is not None and m.rest_s >= self.min_rest_s:
                rest = _max(rest, m.rest_error_rad)
            drift = _max(drift, m.rest_max_error_rad)
        return {
            "executed": self.n_executed,
            "rejected": self.n_rejected,
            "queued": len(self.queue),
            # The next command started before this one came within tolerance (the client moved on early).
            "superseded_before_settling": superseded,
            "max_settle_s": round(settle, 4) if settle is not None else None,
            "max_rest_error_rad": rest,
            "max_error_after_settling_rad": drift,
            "settle_tolerance_rad": self.world.config.settle_tolerance_rad,
            "max_move_s": self.max_move_s,
            "max_queue": self.max_queue,
            "records_kept": self.executed.maxlen,
        }


def _max(a: float | None, b: float | None) -> float | None:
    return b if a is None else a if b is None else max(a, b)
