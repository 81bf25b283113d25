"""What the UR driver station records for its report: every goal (accepted or why not, when it started and ended,
how late, its result, the largest path error and the lowest speed scaling while it ran), every ``set_io`` call, and
every halt (how many control cycles passed between the ``io_states`` saying the block is gone and the cancel
arriving). Bounded: totals over everything, the last :data:`RECORDS_KEPT` of each in full.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Hashable
from dataclasses import dataclass
from typing import Any

from ur3hanoi.interface.urdriver.facts import code_name
from ur3hanoi.interface.urdriver.follower import Outcome
from ur3hanoi.interface.urdriver.goal import Rejection, TrajectoryGoal

RECORDS_KEPT = 100
"""How many goals, IO calls and halts the report keeps in full."""


def _r(x: float | None, n: int = 4) -> float | None:
    return None if x is None else round(x, n)


@dataclass
class GoalRecord:
    """One goal. Times [s] are world times; ``nominal_s`` is its last point's ``time_from_start``."""

    key: str
    points: int
    nominal_s: float
    t_received: float
    accepted: bool = False
    rejection: Rejection | None = None
    t_end: float | None = None
    outcome: Outcome | None = None
    max_path_error_rad: float = 0.0
    min_speed_scaling: float = 1.0

    @property
    def lateness_s(self) -> float | None:
        """How much longer than its nominal duration it ran (None while it runs or when rejected)."""
        return None if self.t_end is None or not self.accepted else self.t_end - self.t_received - self.nominal_s

    def as_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"goal": self.key, "points": self.points, "nominal_s": _r(self.nominal_s),
                               "t_received": _r(self.t_received), "accepted": self.accepted}
        if self.rejection is not None:
            out.update(result=code_name(self.rejection.code), error_string=self.rejection.error_string,
                       reason=self.rejection.reason)
            return out
        o = self.outcome
        out.update(t_end=_r(self.t_end), lateness_s=_r(self.lateness_s), status=None if o is None else o.status,
                   result=None if o is None else code_name(o.code), error_string=None if o is None else o.error_string,
                   max_path_error_rad=_r(self.max_path_error_rad, 6), min_speed_scaling=_r(self.min_speed_scaling))
        return out


@dataclass(frozen=True)
class Halt:
    """The vacuum switch input fell while a block was carried (control cycle ``lost_cycle``); the client's cancel
    arrived ``cycles`` cycles later (``wall_s`` [s] between the ``io_states`` published and the cancel's arrival, on
    the wall clock; None on the CPU clock)."""

    t: float
    lost_cycle: int
    cancel_cycle: int
    wall_s: float | None

    @property
    def cycles(self) -> int:
        return self.cancel_cycle - self.lost_cycle

    def as_dict(self) -> dict[str, Any]:
        return {"t": _r(self.t), "feedback_lost_cycle": self.lost_cycle, "cancel_cycle": self.cancel_cycle,
                "cycles": self.cycles, "wall_ms": None if self.wall_s is None else round(1e3 * self.wall_s, 3)}


class DriverRecords:
    """The station's records (see the module docstring)."""

    def __init__(self, kept: int = RECORDS_KEPT) -> None:
        self.goals: deque[GoalRecord] = deque(maxlen=kept)
        self._by_key: dict[Hashable, GoalRecord] = {}
        self.io_calls: deque[dict[str, Any]] = deque(maxlen=kept)
        self.halts: deque[Halt] = deque(maxlen=kept)
        self.counts = {"received": 0, "accepted": 0, "rejected": 0, "succeeded": 0, "aborted": 0, "canceled": 0,
                       "preempted": 0, "io_calls": 0, "io_refused": 0}
        self._lost: tuple[int, float | None] | None = None  # (cycle, wall time published) of a fallen vacuum switch
        self.program: deque[dict[str, Any]] = deque(maxlen=kept)  # the External Control program's stops and starts

    def received(self, key: Hashable, goal: TrajectoryGoal, t: float, decision: Rejection | None) -> None:
        """A goal was decided at world time ``t``."""
        nominal = (goal.points[-1].time_from_start_s if goal.points else 0.0) + (goal.start_in_s or 0.0)
        rec = GoalRecord(str(key), len(goal.points), nominal, t, decision is None, decision)
        self.counts["received"] += 1
        self.counts["accepted" if decision is None else "rejected"] += 1
        self.goals.append(rec)
        if decision is None:
            self._by_key[key] = rec

    def running(self, key: Hashable | None, path_error: float, scaling: float) -> None:
        """The active goal's state after a cycle."""
        rec = self._by_key.get(key) if key is not None else None
        if rec is not None:
            rec.max_path_error_rad = max(rec.max_path_error_rad, path_error)
            rec.min_speed_scaling = min(rec.min_speed_scaling, scaling)

    def ended(self, outcome: Outcome, t: float) -> None:
        rec = self._by_key.pop(outcome.key, None)
        self.counts[outcome.status] += 1
        if rec is not None:
            rec.t_end, rec.outcome = t, outcome
            rec.max_path_error_rad = max(rec.max_path_error_rad, outcome.max_path_error_rad)

    def program_changed(self, t: float, running: bool) -> None:
        """The External Control program stopped (``running`` False) or started at world time ``t``."""
        self.program.append({"t": _r(t), "running": running})

    def io_call(self, t: float, fun: int, pin: int, state: float, success: bool) -> None:
        self.counts["io_calls" if success else "io_refused"] += 1
        self.io_calls.append({"t": _r(t), "fun": fun, "pin": pin, "state": state, "success": success})

    def switch(self, held_before: bool, held_now: bool, carrying: bool, cycle: int, wall: float | None) -> None:
        """The vacuum switch input of this cycle: a fall while a goal runs with the suction on starts a halt
        measurement."""
        if held_before and not held_now and carrying:
            self._lost = (cycle, wall)

    def canceled(self, t: float, cycle: int, wall: float | None) -> None:
        """A cancel arrived (``wall``: its arrival on the wall clock, None on the CPU clock)."""
        if self._lost is not None:
            lost_cycle, published = self._lost
            self._lost = None
            gap = None if wall is None or published is None else wall - published
            self.halts.append(Halt(t, lost_cycle, cycle, gap))

    def summary(self) -> dict[str, Any]:
        accepted = [g for g in self.goals if g.accepted and g.t_end is not None]
        return {**self.counts,
                "max_lateness_s": _r(max((g.lateness_s or 0.0 for g in accepted), default=None)),
                "max_path_error_rad": _r(max((g.max_path_error_rad for g in accepted), default=None), 6),
                "records_kept": self.goals.maxlen}
