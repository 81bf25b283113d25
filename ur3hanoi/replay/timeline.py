"""What the replay page shows beside the 3-D scene at each moment: the move, the suction state and, for a halted
run, the moment of the halt and its message (:class:`Timeline`, built by :func:`timeline_of_run` from a
simulated run or :func:`timeline_of_plan` from a plan alone). Moves, blocks, towers and heights are shown from 1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour
from ur3hanoi.plan.types import Plan
from ur3hanoi.sim.result import SimResult
from ur3hanoi.station.suction_profile import SuctionProfile

FAULT_KINDS = ("missing", "dropped")
"""Feedback event kinds that halt a run."""


@dataclass(frozen=True)
class Timeline:
    """Per-frame overlay data, on the frame times ``t`` [s] of the recorded poses.

    Attributes:
        t: (F,) frame times [s].
        move: (F,) 0-based move index, -1 before the first move, on the way home and during a halt.
        suction: (F,) suction on (the valve, as ``AIN0`` shows it in a run; as commanded in a plan).
        held: (F,) a block is held (``DIGIN`` bit 0 in a run; as planned in a plan).
        moves: one line per move, 1-based ("block 3 (red): tower 1 height 3 -> tower 3 height 1").
        fault_t: sim time [s] the halt began (None: no fault); fault_message: the run's error line;
            fault_move: the 0-based move it halted in.
        title: the page's heading.
    """

    t: FloatArray
    move: np.ndarray
    suction: np.ndarray
    held: np.ndarray
    moves: tuple[str, ...]
    title: str
    fault_t: float | None = None
    fault_message: str | None = None
    fault_move: int | None = None

    def to_json(self) -> dict[str, Any]:
        return {
            "title": self.title,
            "duration": float(self.t[-1]),
            "t": [round(float(v), 4) for v in self.t],
            "move": [int(v) for v in self.move],
            "suction": [int(v) for v in self.suction],
            "held": [int(v) for v in self.held],
            "moves": list(self.moves),
            "fault": None if self.fault_t is None else {
                "t": round(self.fault_t, 4), "message": self.fault_message,
                "move": None if self.fault_move is None else self.fault_move + 1},
        }


def move_labels(plan: Plan) -> tuple[str, ...]:
    return tuple(f"block {m.block + 1} ({block_colour(m.block)}): tower {m.from_tower + 1} height "
                 f"{m.from_height + 1} -> tower {m.to_tower + 1} height {m.to_height + 1}" for m in plan.moves)


def _plan_samples(plan: Plan, t: FloatArray) -> np.ndarray:
    tr = plan.trajectory
    return np.minimum(np.rint(t * tr.rate_hz).astype(int), len(tr.t) - 1)


def timeline_of_plan(plan: Plan, t: FloatArray, title: str) -> Timeline:
    """The plan as intended: its move index and commanded suction at each frame time ``t`` [s]."""
    tr = plan.trajectory
    k = _plan_samples(plan, t)
    suction = tr.suction[k].astype(bool)
    return Timeline(t=t, move=tr.move_index[k].astype(int), suction=suction, held=suction.copy(),
                    moves=move_labels(plan), title=title)


def timeline_of_run(plan: Plan, result: SimResult, t: FloatArray, title: str,
                    suction: SuctionProfile | None = None) -> Timeline:
    """A simulated run at frame times ``t`` [s]: the plan's move until the halt (none after it), the suction valve
    and ``DIGIN`` from the run's ``gripper_input`` trace (the valve is on when ``AIN0`` is above the midpoint of the
    suction-off and suction-on-empty levels of ``suction``, the station's feedback profile; default the plan's
    station's), and the halt's time and message."""
    cfg = suction if suction is not None else plan.station.suction
    move = _plan_samples(plan, t)
    move = plan.trajectory.move_index[move].astype(int)
    fb = result.feedback_trace
    if len(fb):
        i = np.clip(np.searchsorted(fb[:, 0], t - 1e-9), 0, len(fb) - 1)
        held = fb[i, 1].astype(int) & 1 == 1
        suction_on = fb[i, 2] > 0.5 * (cfg.ain0_off + cfg.ain0_free)
    else:
        held = np.zeros(len(t), dtype=bool)
        suction_on = np.zeros(len(t), dtype=bool)
    fault_t = None
    if result.status == "halted":
        times = [e.t for e in result.feedback_events if e.kind in FAULT_KINDS]
        trace = result.joint_trace
        if times:
            fault_t = float(min(times))
        elif trace.halt_start is not None and trace.halt_start < len(trace.t):
            fault_t = float(trace.t[trace.halt_start])
        else:
            fault_t = float(t[-1])
        move = np.where(t >= fault_t, -1, move)
    message = None if result.error is None else " ".join(result.error.split())
    return Timeline(t=t, move=move, suction=suction_on, held=held, moves=move_labels(plan), title=title,
                    fault_t=fault_t, fault_message=message if fault_t is not None else None,
                    fault_move=result.fault_move if fault_t is not None else None)
