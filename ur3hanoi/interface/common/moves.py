"""How both protocols' solves name a move on their log: the same line for the course's topics and the UR driver.

:func:`describe_move` is printed by :func:`ur3hanoi.interface.course.solve.run_lab_solve` and
:func:`ur3hanoi.interface.urdriver.solve.run_driver_solve`, so a log reads the same whichever protocol moved the arm.
"""

from __future__ import annotations

from ur3hanoi.hanoi import Move, block_colour


def describe_move(move: Move) -> str:
    """``block 3 (red): tower 1 height 3 -> tower 3 height 1`` (numbered from 1)."""
    return (f"block {move.block + 1} ({block_colour(move.block)}): tower {move.from_tower + 1} height "
            f"{move.from_height + 1} -> tower {move.to_tower + 1} height {move.to_height + 1}")
