"""The lab program's suction check while ``solve`` streams a plan: after every sample, a block must be held at the
end of every GRASP_DWELL and in every cycle of a carrying phase; a failed check is a :class:`Fault` (what the halt
then reports, with the diagnosis of :mod:`ur3hanoi.sim.diagnosis`).

Numbering: internally 0-based (moves, blocks, samples); messages are 1-based like the lab.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour
from ur3hanoi.plan import Phase, Plan
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.diagnosis import missed_grasp, missing_block
from ur3hanoi.sim.result import FeedbackEvent
from ur3hanoi.sim.scene import TaskScene
from ur3hanoi.sim.suction import GripperInput, SuctionCup


@dataclass(frozen=True)
class Fault:
    """A failed suction check: at plan sample ``k``, sim time ``t`` [s] (0-based move and block).

    ``resting`` holds the position [m, world] of every block that rested in the scene when the fault was detected
    (all but the one lost from the cup), to find the blocks knocked out of place afterwards.
    """

    move: int
    block: int
    message: str
    t: float
    k: int
    resting: dict[int, FloatArray] = field(default_factory=dict)


class SuctionCheck:
    """The suction check of one plan's run (see the module docstring); feedback events go to ``events``."""

    def __init__(self, plan: Plan, scene: TaskScene, cup: SuctionCup, config: SimConfig,
                 events: list[FeedbackEvent]) -> None:
        self.plan, self.scene, self.cup, self.cfg, self.events = plan, scene, cup, config, events
        tr = plan.trajectory
        # Per-sample flags as Python lists, computed once: the streaming loop is Python-bound (mj_step aside).
        grasp = tr.phase == Phase.GRASP_DWELL
        self.grasping: list[bool] = grasp.tolist()
        self.dwell_ends: list[bool] = (grasp & ~np.append(grasp[1:], False)).tolist()  # a block must be held
        self.carrying: list[bool] = np.isin(tr.phase, [p for p in Phase if p.carrying]).tolist()  # held every cycle
        # Per move: the closest the cup (suction point) came to the grasp point of the block to pick during the
        # grasp dwell [m], for the message when nothing was grasped.
        self.closest_grasp: dict[int, float] = {}

    def track_grasp(self, k: int, mv: int) -> None:
        """During a grasp dwell with nothing grasped yet, update the closest approach of the cup to the grasp point
        of move ``mv``'s block (see the grasp rule, :attr:`ur3hanoi.sim.SuctionConfig.grasp_radius`)."""
        if not self.grasping[k] or self.cup.attached is not None:
            return
        block = self.plan.moves[mv].block
        if block in self.scene.block_body:
            p_cup = self.scene.data.site_xpos[self.scene.site_id]
            dist = float(np.linalg.norm(self.cup.expected_suction_point(block) - p_cup))
            self.closest_grasp[mv] = min(dist, self.closest_grasp.get(mv, math.inf))

    def after_sample(self, k: int, mv: int, fb: GripperInput) -> Fault | None:
        """The lab program's check after sample ``k`` of move ``mv``: a block held where one must be, else the
        fault."""
        dwell_end = self.dwell_ends[k]
        if (dwell_end or self.carrying[k]) and not fb.held:
            return self._fault(k, mv, fb, "missing" if dwell_end else "dropped")
        if dwell_end:
            attached = self.cup.attached
            self.events.append(FeedbackEvent(fb.t, "grasp", mv, attached if attached is not None else -1,
                                             fb.digin, fb.ain0))
        return None

    def _fault(self, k: int, mv: int, fb: GripperInput, kind: str) -> Fault:
        moves = self.plan.moves
        move = moves[mv]
        self.events.append(FeedbackEvent(fb.t, kind, mv, move.block, fb.digin, fb.ain0))
        sensed = f"(DIGIN={fb.digin}, AIN0={fb.ain0:.2f} V)"
        block = move.block
        if kind == "dropped":
            what = (f"{block_colour(block)} block {block + 1} was dropped while carrying it from tower "
                    f"{move.from_tower + 1} to tower {move.to_tower + 1} {sensed}")
        else:
            missed = missed_grasp(self.plan, mv, self.closest_grasp.get(mv), self.cfg.suction.grasp_radius)
            block, what = missing_block(self.plan, self.scene, mv, sensed, self.cfg.place_tolerance_m, missed)
        msg = f"suction fault in move {mv + 1}/{len(moves)}: {what}; halted, suction off, arm returned home"
        resting = {b: self.scene.block_pos(b) for b in self.scene.block_body if kind == "missing" or b != block}
        return Fault(mv, block, msg, fb.t, k, resting)
