"""The client and the station in one process on the CPU clock: a
:class:`~ur3hanoi.interface.urdriver.client.DriverTransport` straight into a
:class:`~ur3hanoi.interface.urdriver.station.DriverStation`, without a middleware or the wall clock.

:class:`LoopbackTransport` runs one control cycle of the station per :meth:`~LoopbackTransport.wait` and reads its
:attr:`~ur3hanoi.interface.urdriver.station.DriverStation.output` as a binding would; its clock is the station's world
time, so the client's timeouts and dwells count simulated seconds and a 27 s solve runs as fast as the CPU allows.
The tests of the neutral client and station use it, and it shows what a binding does with each output.
"""

from __future__ import annotations

from collections.abc import Hashable

from ur3hanoi.interface.urdriver.client import DriverState, GoalResult
from ur3hanoi.interface.urdriver.goal import TrajectoryGoal
from ur3hanoi.interface.urdriver.joint_record import JointRecord
from ur3hanoi.interface.urdriver.station import DriverStation


class LoopbackGoal:
    """A goal sent through :class:`LoopbackTransport` (a :class:`~ur3hanoi.interface.urdriver.client.GoalHandle`)."""

    def __init__(self, transport: LoopbackTransport, key: Hashable) -> None:
        self.transport, self.key = transport, key
        self.outcome: GoalResult | None = None

    def done(self) -> bool:
        return self.outcome is not None

    def result(self) -> GoalResult:
        assert self.outcome is not None, "result() before done()"
        return self.outcome

    def cancel(self) -> None:
        self.transport.station.on_cancel(self.key)


class LoopbackTransport:
    """A driver transport into ``station`` on the CPU clock (see the module docstring)."""

    def __init__(self, station: DriverStation) -> None:
        self.station = station
        self.where = "the loopback station"
        self.goals: dict[Hashable, LoopbackGoal] = {}
        self._sent = 0
        self.cycles = 0
        self.record = JointRecord()

    def connect(self) -> None:
        self.wait(0.0)

    def now(self) -> float:
        return self.station.world.time

    def latest(self) -> DriverState:
        out = self.station.output
        return DriverState(out.q, out.t_s, out.io, out.speed_scaling, out.program_running)

    def send_goal(self, goal: TrajectoryGoal) -> LoopbackGoal:
        self._sent += 1
        key = f"goal-{self._sent}"
        handle = self.goals[key] = LoopbackGoal(self, key)
        self.station.on_goal(key, goal)
        return handle

    def set_io(self, fun: int, pin: int, state: float) -> bool:
        return self.station.set_io(fun, pin, state) is not None

    def wait(self, timeout_s: float) -> None:
        """One control cycle of the station, then its output handed to the goals, as a binding does."""
        self.station.cycle()
        self.cycles += 1
        out = self.station.output
        self.record.add(out.t_s, out.q)
        for key, rejection in out.decisions:
            if rejection is not None and key in self.goals:
                self.goals.pop(key).outcome = GoalResult("rejected", int(rejection.code), rejection.error_string)
        for key, outcome in out.results:
            if key in self.goals:
                code = None if outcome.status in ("canceled", "preempted") else int(outcome.code)
                self.goals.pop(key).outcome = GoalResult(outcome.status, code, outcome.error_string)

    def close(self) -> None:
        self.goals.clear()
