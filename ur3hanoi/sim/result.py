"""What a run of the executor reports: :class:`SimResult` with its :class:`FeedbackEvent` list, the
:class:`FinalBlock` positions read from the simulation, and the :class:`JointTrace` of reference and joints.

Numbering: fields are 0-based; :meth:`SimResult.as_dict` (the ``solve --json`` output) is 1-based like the lab.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour


@dataclass(frozen=True)
class FeedbackEvent:
    """A suction check or transition: ``kind`` in {"grasp", "release", "check_ok", "missing", "dropped",
    "drop_injected"}; times [s]; ``move``/``block`` 0-based (-1 if none)."""

    t: float
    kind: str
    move: int
    block: int
    digin: int
    ain0: float

    def as_dict(self) -> dict[str, Any]:
        return {"t": round(self.t, 6), "kind": self.kind, "move": self.move + 1 if self.move >= 0 else None,
                "block": self.block + 1 if self.block >= 0 else None, "digin": self.digin,
                "ain0": round(self.ain0, 4)}


@dataclass(frozen=True)
class FinalBlock:
    """Where a block ended: ``tower``/``height`` 0-based (None when it is in no slot), ``xyz`` [m, world]."""

    block: int
    tower: int | None
    height: int | None
    xyz: tuple[float, float, float]

    def as_dict(self) -> dict[str, Any]:
        return {"block": self.block + 1, "colour": block_colour(self.block),
                "tower": None if self.tower is None else self.tower + 1,
                "height": None if self.height is None else self.height + 1,
                "xyz": [round(v, 6) for v in self.xyz]}


@dataclass(frozen=True)
class DisplacedBlock:
    """A block knocked out of place after a halt: it rested at ``tower``/``height`` (0-based; None: in no slot)
    when the fault was detected and has since moved ``moved_m`` [m] (e.g. hit by the dropped block)."""

    block: int
    tower: int | None
    height: int | None
    moved_m: float

    def describe(self) -> str:
        where = "" if self.tower is None or self.height is None else \
            f" at tower {self.tower + 1} height {self.height + 1}"
        return (f"{block_colour(self.block)} block {self.block + 1} was knocked {self.moved_m * 1e3:.1f} mm out of "
                f"its place{where}")

    def as_dict(self) -> dict[str, Any]:
        return {"block": self.block + 1, "colour": block_colour(self.block),
                "tower": None if self.tower is None else self.tower + 1,
                "height": None if self.height is None else self.height + 1,
                "moved_mm": round(self.moved_m * 1e3, 3)}


@dataclass(frozen=True)
class JointTrace:
    """The joint reference the executor streamed and the simulated arm joints, one row per control cycle.

    Row 0 is the start (at rest on the plan's first sample), row k the end of control cycle k. Rows
    ``[0, halt_start)`` stream the plan (row k is plan sample k); rows ``[halt_start, settle_start)`` are the halt
    after a suction fault (decelerate to rest, vent the vacuum, return home); rows ``[settle_start, N)`` hold the
    final pose while the blocks settle. Without a fault ``halt_start`` is None and the halt rows are empty.

    Attributes:
        t: (N,) sim time [s].
        q_ref, qd_ref, qdd_ref: (N, 6) the streamed reference [rad, rad/s, rad/s^2]; the servo is commanded
            ``q_ref + (kv/kp) qd_ref`` (+ ``M(q) qdd_ref / kp``), interpolated linearly over the cycle.
        q, qd: (N, 6) the simulated joints at the end of the cycle [rad, rad/s]. Their acceleration over a cycle
            is ``diff(qd) / diff(t)``; MuJoCo's instantaneous ``qacc`` is not recorded: it swings to 10-20 times the
            planned acceleration within a cycle (2 ms steps, a command change every cycle) even on a smooth plan.
        halt_start, settle_start: row indices (see above).
    """

    t: FloatArray
    q_ref: FloatArray
    qd_ref: FloatArray
    qdd_ref: FloatArray
    q: FloatArray
    qd: FloatArray
    halt_start: int | None
    settle_start: int

    @staticmethod
    def empty() -> JointTrace:
        z = np.zeros((0, 6))
        return JointTrace(np.zeros(0), z, z, z, z, z, None, 0)


@dataclass(frozen=True)
class SimResult:
    """Outcome of :func:`ur3hanoi.sim.run_plan`. ``status``: "solved", "halted" (suction fault: ``run_plan``
    raises :class:`ur3hanoi.errors.SuctionFaultError` carrying this result, exit 3) or "failed" (the final state
    does not match the plan, exit 2)."""

    status: str
    exit_code: int
    error: str | None
    moves_completed: int
    moves_total: int
    final_blocks: tuple[FinalBlock, ...]
    suction_on_at_end: bool
    at_home_at_end: bool
    sim_time_s: float
    wall_time_s: float
    max_tracking_error_rad: float
    feedback_events: tuple[FeedbackEvent, ...]
    fault_move: int | None = None
    fault_block: int | None = None
    fault_tower: int | None = None
    detection_latency_s: float | None = None
    # Blocks knocked out of place after a halt (the final verification of a halted run).
    displaced_blocks: tuple[DisplacedBlock, ...] = ()
    warnings: dict[str, int] = field(default_factory=dict)
    # gripper_input every control cycle: columns t [s], DIGIN, AIN0 [V] (for plots; not in the JSON).
    feedback_trace: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    # Streamed reference and simulated joints every control cycle, the halt included (for checks; not in the JSON).
    joint_trace: JointTrace = field(default_factory=JointTrace.empty)

    @property
    def realtime_factor(self) -> float:
        return self.sim_time_s / self.wall_time_s if self.wall_time_s > 0 else math.inf

    def as_dict(self) -> dict[str, Any]:
        return {
            "status": self.status,
            "exit_code": self.exit_code,
            "moves_completed": self.moves_completed,
            "moves_total": self.moves_total,
            "error": self.error,
            "final_blocks": [b.as_dict() for b in self.final_blocks],
            "suction_on_at_end": self.suction_on_at_end,
            "at_home_at_end": self.at_home_at_end,
            "sim_time_s": round(self.sim_time_s, 4),
            "wall_time_s": round(self.wall_time_s, 4),
            "realtime_factor": round(self.realtime_factor, 2),
            "max_tracking_error_rad": self.max_tracking_error_rad,
            "max_tracking_error_deg": math.degrees(self.max_tracking_error_rad),
            "fault": None if self.fault_move is None else {
                "move": self.fault_move + 1,
                "block": None if self.fault_block is None else self.fault_block + 1,
                "tower": None if self.fault_tower is None else self.fault_tower + 1,
                "detection_latency_s": self.detection_latency_s,
                "displaced_blocks": [b.as_dict() for b in self.displaced_blocks],
            },
            "mujoco_warnings": self.warnings,
            "feedback_events": [e.as_dict() for e in self.feedback_events],
        }
