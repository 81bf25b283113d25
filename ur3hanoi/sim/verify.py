"""What the simulation state says about the task, read the same way by ``solve`` and by the ``movej`` world: where
every block is (:func:`locate_blocks`), whether the arm is home (:func:`at_home`), and ``solve``'s final check
(:func:`final_check`).

Numbering: 0-based in, 1-based in the messages (like the lab).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import block_colour
from ur3hanoi.sim.result import FinalBlock
from ur3hanoi.sim.scene import TaskScene, slot_of


def locate_blocks(scene: TaskScene, centers: FloatArray, place_tolerance_m: float) -> tuple[FinalBlock, ...]:
    """Where every block of ``scene`` is now, in block order: the slot (tower, height) whose block centre
    (``centers``, :func:`~ur3hanoi.sim.slot_centers`) is within ``place_tolerance_m`` [m], else none."""
    out = []
    for b in sorted(scene.block_body):
        xyz = scene.block_pos(b)
        slot = slot_of(centers, xyz, place_tolerance_m)
        out.append(FinalBlock(b, None if slot is None else slot[0], None if slot is None else slot[1],
                              (float(xyz[0]), float(xyz[1]), float(xyz[2]))))
    return tuple(out)


def at_home(scene: TaskScene, home_tolerance_rad: float) -> bool:
    """Every arm joint within ``home_tolerance_rad`` [rad] of the station's home pose."""
    return bool(np.max(np.abs(scene.arm_q() - scene.station.q_home_array)) <= home_tolerance_rad)


def final_check(final: Sequence[FinalBlock], end_tower: int, place_tolerance_m: float) -> str | None:
    """``solve``'s final check of a run without a fault: every block at its own height on ``end_tower``. None when
    it passes, else the message naming every block out of place."""
    wrong = [fb for fb in final if (fb.tower, fb.height) != (end_tower, fb.block)]
    if not wrong:
        return None
    return "final state check failed: " + "; ".join(
        f"{block_colour(fb.block)} block {fb.block + 1} at {np.round(fb.xyz, 4).tolist()} is not within "
        f"{place_tolerance_m * 1e3:.0f} mm of tower {end_tower + 1} height {fb.block + 1}" for fb in wrong)
