"""The Tower of Hanoi puzzle on a station's grid: optimal move sequences and a legality checker.

Internally towers, heights and blocks are numbered from 0 (block 0 = the bottom/largest, green); the CLI and
JSON output number them from 1, as the lab does.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from ur3hanoi.errors import PuzzleError

BLOCK_COLOURS: tuple[str, ...] = ("green", "yellow", "red")


@dataclass(frozen=True)
class Move:
    """One pick-and-place: ``block`` (0 = largest) from (from_tower, from_height) to (to_tower, to_height)."""

    block: int
    from_tower: int
    from_height: int
    to_tower: int
    to_height: int

    def as_lab_dict(self) -> dict[str, int]:
        """1-based numbering, as on the lab's command line and in the JSON output."""
        return {
            "block": self.block + 1,
            "from_tower": self.from_tower + 1,
            "from_height": self.from_height + 1,
            "to_tower": self.to_tower + 1,
            "to_height": self.to_height + 1,
        }


def block_colour(block: int) -> str:
    return BLOCK_COLOURS[block] if block < len(BLOCK_COLOURS) else f"block{block + 1}"


def _start_stacks(n_blocks: int, start: int, n_towers: int) -> list[list[int]]:
    """Tower contents (bottom first) with every block on ``start``."""
    stacks: list[list[int]] = [[] for _ in range(n_towers)]
    stacks[start] = list(range(n_blocks))
    return stacks


def validate_instance(n_blocks: int, start: int, end: int, n_towers: int, n_heights: int) -> None:
    """Reject start == end, towers outside the grid and more blocks than heights (0-based towers)."""
    if n_towers < 3:
        raise PuzzleError(f"the grid has {n_towers} towers: the puzzle needs at least 3")
    for name, t in (("start", start), ("end", end)):
        if not 0 <= t < n_towers:
            raise PuzzleError(f"{name} tower {t + 1} is outside the grid: expected 1..{n_towers}")
    if start == end:
        raise PuzzleError(f"start and end tower are both {start + 1}: expected two different towers")
    if not 1 <= n_blocks <= n_heights:
        raise PuzzleError(f"{n_blocks} blocks is invalid: expected 1..{n_heights} (the grid's heights)")


def solve_hanoi(n_blocks: int, start: int, end: int, n_towers: int = 3, n_heights: int | None = None) -> list[Move]:
    """The optimal 2^n - 1 moves taking ``n_blocks`` from tower ``start`` to tower ``end`` (0-based).

    Only three towers are used (start, end and the lowest-numbered other one), as in the lab.
    """
    validate_instance(n_blocks, start, end, n_towers, n_heights if n_heights is not None else n_blocks)
    via = next(t for t in range(n_towers) if t not in (start, end))
    stacks = _start_stacks(n_blocks, start, n_towers)
    moves: list[Move] = []

    # Iterative form of the recursion (no recursion limit for tall synthetic grids).
    work: list[tuple[int, int, int, int]] = [(n_blocks, start, end, via)]
    while work:
        n, src, dst, spare = work.pop()
        if n == 0:
            continue
        if n < 0:  # marker: move the top block of src to dst (its block and heights come from the replayed stacks)
            block = stacks[src].pop()
            moves.append(Move(block, src, len(stacks[src]), dst, len(stacks[dst])))
            stacks[dst].append(block)
            continue
        work.append((n - 1, spare, dst, src))
        work.append((-1, src, dst, spare))
        work.append((n - 1, src, spare, dst))
    return moves


def check_sequence(moves: Sequence[Move], n_blocks: int, start: int, end: int, n_towers: int,
                   n_heights: int) -> None:
    """Replay ``moves`` from all blocks on ``start`` and require a legal game ending with all blocks on ``end``.

    Legal: only a tower's top block moves, it lands on top of the destination (no floating, no overwriting) and
    never on a smaller block, and every index is inside the grid.

    Raises:
        PuzzleError: naming the first illegal move (1-based) and why.
    """
    validate_instance(n_blocks, start, end, n_towers, n_heights)
    stacks = _start_stacks(n_blocks, start, n_towers)
    for i, m in enumerate(moves, start=1):
        where = f"move {i} (block {m.block + 1}, tower {m.from_tower + 1} -> {m.to_tower + 1})"
        for t in (m.from_tower, m.to_tower):
            if not 0 <= t < n_towers:
                raise PuzzleError(f"{where}: tower {t + 1} is outside the grid 1..{n_towers}")
        src, dst = stacks[m.from_tower], stacks[m.to_tower]
        if m.from_tower == m.to_tower:
            raise PuzzleError(f"{where}: source and destination are the same tower")
        if not src or src[-1] != m.block:
            top = f"block {src[-1] + 1}" if src else "nothing"
            raise PuzzleError(f"{where}: only the top block can move, tower {m.from_tower + 1} has {top} on top")
        if m.from_height != len(src) - 1:
            raise PuzzleError(f"{where}: block is at height {len(src)}, not {m.from_height + 1}")
        if m.to_height != len(dst):
            raise PuzzleError(f"{where}: destination height {m.to_height + 1} must be {len(dst) + 1} "
                              "(blocks rest on the top of the tower, none floats)")
        if m.to_height >= n_heights:
            raise PuzzleError(f"{where}: height {m.to_height + 1} is above the grid's {n_heights} heights")
        if dst and dst[-1] > m.block:
            raise PuzzleError(f"{where}: block {m.block + 1} cannot be placed on the smaller block {dst[-1] + 1}")
        dst.append(src.pop())
    if stacks[end] != list(range(n_blocks)):
        raise PuzzleError(f"after {len(moves)} moves the blocks are not all on tower {end + 1}: {stacks}")


def stacks_before_moves(moves: Sequence[Move], n_blocks: int, start: int, n_towers: int) -> list[list[list[int]]]:
    """Tower contents (bottom first, 0-based blocks) before each move, plus the final state: len(moves) + 1 entries.

    The moves are replayed without legality checks (use :func:`check_sequence` for that).
    """
    stacks = _start_stacks(n_blocks, start, n_towers)
    out = [[list(s) for s in stacks]]
    for m in moves:
        stacks[m.to_tower].append(stacks[m.from_tower].pop())
        out.append([list(s) for s in stacks])
    return out
