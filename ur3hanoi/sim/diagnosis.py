"""Why a suction check failed, read from the simulation state: what the executor says after a fault.

The lab program only knows that no block is held. The simulator knows where every block is, so a halt names
what actually happened:

- :func:`missing_block`: a grasp found nothing. The block the move wanted may not be the missing one: in a
  stacked tower the blocks above a missing one rest one level lower, so the first pick (the top) finds nothing
  whichever block was removed. Or every block is where the plan expects it and the cup did not reach its grasp
  point (a table entry off): then the closest approach of the cup is given.
- :func:`displaced_blocks`: after a halt, the blocks knocked out of place (e.g. by the dropped block), found by
  comparing their positions with those at the moment of the fault (finer than the 5 mm slot tolerance: a knock of
  3 mm leaves a block "in" its slot).

Numbering: 0-based in, 1-based in the messages (like the lab).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour, stacks_before_moves
from ur3hanoi.plan import Phase, Plan
from ur3hanoi.sim.result import DisplacedBlock
from ur3hanoi.sim.scene import TaskScene, slot_centers, slot_of


def _slot_text(slot: tuple[int, int] | None, xyz: FloatArray) -> str:
    if slot is None:
        return f"in no slot at {np.round(xyz, 4).tolist()} m"
    return f"at tower {slot[0] + 1} height {slot[1] + 1}"


def expected_slots(plan: Plan, move: int) -> dict[int, tuple[int, int]]:
    """Where the plan expects every block (0-based tower, height) before ``move``, all blocks present."""
    moves = plan.moves
    n_blocks = max(m.block for m in moves) + 1
    stacks = stacks_before_moves(moves, n_blocks, moves[0].from_tower, plan.station.n_towers)[move]
    return {b: (t, h) for t, stack in enumerate(stacks) for h, b in enumerate(stack)}


def missed_grasp(plan: Plan, move: int, closest_m: float | None, grasp_radius_m: float) -> str:
    """How close the cup came to the grasp point of ``move``'s block in its grasp dwell (``closest_m`` [m]) and
    at which waypoint (the dwell's target: a table entry for a table plan); "" when not measured."""
    if closest_m is None:
        return ""
    target = next((s.target for s in plan.segments if s.phase == Phase.GRASP_DWELL and s.move_index == move), "")
    at = f" at {target}" if target else ""
    return (f"the cup (suction point) came no closer than {closest_m * 1e3:.1f} mm to its grasp point{at} (a grasp "
            f"needs {grasp_radius_m * 1e3:g} mm or less)")


def missing_block(plan: Plan, scene: TaskScene, move: int, sensed: str, place_tolerance_m: float,
                  missed: str = "") -> tuple[int, str]:
    """Why nothing was picked in ``move``: (the block actually missing, the message part naming it).

    ``sensed`` is the feedback quoted in the message; ``missed`` the text of :func:`missed_grasp`.
    """
    mv = plan.moves[move]
    expected = expected_slots(plan, move)
    absent = [b for b in sorted(expected) if b not in scene.block_body]
    if absent == [mv.block]:  # the block to pick is the one that is gone: the plain message says it all
        return mv.block, (f"{block_colour(mv.block)} block {mv.block + 1} is missing at tower {mv.from_tower + 1} "
                          f"height {mv.from_height + 1} {sensed}")
    centers = slot_centers(plan.station)
    displaced = []
    for b in sorted(scene.block_body):
        xyz = scene.block_pos(b)
        slot = slot_of(centers, xyz, place_tolerance_m)
        if slot != expected[b]:
            displaced.append((b, slot, xyz))
    if not absent and not displaced and missed:
        # Every block is where the plan expects it: the cup did not reach the block (e.g. a table entry off).
        return mv.block, (f"{block_colour(mv.block)} block {mv.block + 1} at tower {mv.from_tower + 1} height "
                          f"{mv.from_height + 1} was not grasped {sensed}: {missed}")
    absent += [b for b, slot, _ in displaced if slot is None]
    missing = absent[0] if absent else mv.block
    t, h = expected[missing]
    text = (f"no block to pick at tower {mv.from_tower + 1} height {mv.from_height + 1}, where "
            f"{block_colour(mv.block)} block {mv.block + 1} should be {sensed}: ")
    text += (f"{block_colour(missing)} block {missing + 1} is missing from tower {t + 1} height {h + 1}" if absent
             else f"{block_colour(missing)} block {missing + 1} is not there")
    found = [f"{block_colour(b)} block {b + 1} is {_slot_text(slot, xyz)}" for b, slot, xyz in displaced
             if slot is not None]
    return missing, text + (f" ({', '.join(found)})" if found else "")


def displaced_blocks(plan: Plan, scene: TaskScene, resting: Mapping[int, FloatArray], knock_tolerance_m: float,
                     place_tolerance_m: float) -> list[DisplacedBlock]:
    """The blocks of ``resting`` (position [m, world] at the fault) that have since moved farther than
    ``knock_tolerance_m``, with the slot they rested in."""
    out = []
    centers = slot_centers(plan.station)
    for b, before in sorted(resting.items()):
        moved = float(np.linalg.norm(scene.block_pos(b) - before))
        if moved > knock_tolerance_m:
            slot = slot_of(centers, before, place_tolerance_m)
            out.append(DisplacedBlock(b, None if slot is None else slot[0], None if slot is None else slot[1], moved))
    return out
