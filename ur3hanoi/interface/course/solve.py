"""The lab program, done right: solve the puzzle through an arm interface with the lab's suction checks.

:func:`run_lab_solve` is what ``lab2_exec.py`` must do (the manual, sections 2.5-2.6): for every move of the optimal
solution go above the block, down to it, suction on, **check the block is held** (``DIGIN`` bit 0), lift, carry,
lower it **checking it stays held all the way**, suction off, back up; finally home. When the feedback says no
block is held where one must be, it halts like the lab asks: suction off, arm home, then
:class:`~ur3hanoi.errors.SuctionFaultError` (exit code 3) with a one-line message.

The arm is any object with the :class:`Arm` methods: :class:`ur3hanoi.interface.course.client.TopicArm`, bound to ROS 1
(``ros-station`` or the real UR3) or ROS 2 (``ros2-station`` or the course's UR3e bridge); tests use a fake.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PuzzleError, SuctionFaultError
from ur3hanoi.hanoi import Move, block_colour, solve_hanoi
from ur3hanoi.interface.common.moves import describe_move


class Arm(Protocol):
    """What the solver needs from the robot (joint angles [rad], controller convention)."""

    def move(self, q: FloatArray, watch: Callable[[], None] | None = None) -> None:
        """Move to ``q`` and return once there; call ``watch`` while waiting (it may raise to abort the wait)."""

    def suction(self, on: bool) -> None:
        """Switch the suction output without moving."""

    def held(self) -> bool:
        """The vacuum switch: True when a block is held (``DIGIN`` bit 0)."""

    def wait_until(self, predicate: Callable[[], bool], timeout_s: float) -> bool:
        """Wait until ``predicate()`` is true (True) or ``timeout_s`` [s] passed (False)."""

    def feedback_text(self) -> str:
        """The last suction feedback for messages, e.g. ``DIGIN=0, AIN0=1.45 V``."""


@dataclass(frozen=True)
class LabSolveConfig:
    """Timing of the suction checks.

    Attributes:
        grasp_timeout_s: after suction on, wait at most this long [s] for the vacuum switch (the lab's programs
            sleep a fixed 1 s; waiting for the switch is as safe and usually faster).
        release_timeout_s: after suction off, wait at most this long [s] for the switch to clear.
        release_dwell_s: then wait this long [s] before lifting, so the vacuum has vented.
    """

    grasp_timeout_s: float = 1.0
    release_timeout_s: float = 0.5
    release_dwell_s: float = 0.1


@dataclass(frozen=True)
class LabSolveResult:
    """A completed solve: the moves, all done, and the wall time [s]."""

    moves: tuple[Move, ...]
    wall_time_s: float


class _BlockLostError(Exception):
    def __init__(self, kind: str) -> None:
        super().__init__(kind)
        self.kind = kind


def run_lab_solve(arm: Arm, Q: FloatArray, home: FloatArray, start: int, end: int, n_blocks: int,
                  config: LabSolveConfig | None = None, log: Callable[[str], None] | None = None) -> LabSolveResult:
    """Solve ``n_blocks`` from tower ``start`` to ``end`` (0-based) with the table ``Q[tower, height, k]``
    (k = 0 on, 1 above; shape (towers, heights, 2, 6) [rad]) and the lab's checks (see the module docstring).

    Raises:
        PuzzleError: bad towers or block count for the table.
        SuctionFaultError: a block was missing or dropped; the arm has halted (suction off, at ``home``).
    """
    cfg = config if config is not None else LabSolveConfig()
    say = log if log is not None else (lambda _s: None)
    if Q.ndim != 4 or Q.shape[2:] != (2, 6):
        raise PuzzleError(f"table shape {Q.shape} is invalid: expected (towers, heights, 2, 6)")
    moves = tuple(solve_hanoi(n_blocks, start, end, Q.shape[0], Q.shape[1]))
    t0 = time.monotonic()

    def check_held() -> None:
        if not arm.held():
            raise _BlockLostError("dropped")

    arm.move(home)
    for i, mv in enumerate(moves):
        say(f"move {i + 1}/{len(moves)}: {describe_move(mv)}")
        pick, place = Q[mv.from_tower, mv.from_height], Q[mv.to_tower, mv.to_height]
        try:
            arm.move(pick[1])
            arm.move(pick[0])
            arm.suction(True)
            if not arm.wait_until(arm.held, cfg.grasp_timeout_s):
                raise _BlockLostError("missing")
            arm.move(pick[1], watch=check_held)
            arm.move(place[1], watch=check_held)
            arm.move(place[0], watch=check_held)
        except _BlockLostError as lost:
            feedback = arm.feedback_text()
            arm.suction(False)
            arm.move(home)
            where = (f"at tower {mv.from_tower + 1} height {mv.from_height + 1}" if lost.kind == "missing"
                     else f"while carrying it from tower {mv.from_tower + 1} to tower {mv.to_tower + 1}")
            raise SuctionFaultError(
                f"suction fault in move {i + 1}/{len(moves)}: {block_colour(mv.block)} block {mv.block + 1} "
                f"{'is missing' if lost.kind == 'missing' else 'was dropped'} {where} ({feedback}); halted, "
                "suction off, arm returned home") from None
        arm.suction(False)
        arm.wait_until(lambda: not arm.held(), cfg.release_timeout_s)
        arm.wait_until(lambda: False, cfg.release_dwell_s)
        arm.move(place[1])
    arm.move(home)
    return LabSolveResult(moves, time.monotonic() - t0)
