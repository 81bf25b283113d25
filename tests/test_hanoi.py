"""Tower of Hanoi solver and legality checker."""

from __future__ import annotations

import itertools

import pytest

from ur3hanoi.errors import PuzzleError
from ur3hanoi.hanoi import Move, check_sequence, solve_hanoi, stacks_before_moves, validate_instance


@pytest.mark.parametrize("n", range(1, 11))
@pytest.mark.parametrize(("start", "end"), list(itertools.permutations(range(3), 2)))
def test_optimal_and_legal(n: int, start: int, end: int) -> None:
    moves = solve_hanoi(n, start, end, 3, n)
    assert len(moves) == 2**n - 1
    check_sequence(moves, n, start, end, 3, n)
    assert stacks_before_moves(moves, n, start, 3)[-1][end] == list(range(n))


def test_lab_dict_is_one_based() -> None:
    m = solve_hanoi(1, 0, 2, 3, 3)[0]
    assert m.as_lab_dict() == {"block": 1, "from_tower": 1, "from_height": 1, "to_tower": 3, "to_height": 1}


@pytest.mark.parametrize(("n", "start", "end", "msg"), [
    (3, 0, 0, "both"), (3, 0, 3, "outside"), (3, -1, 1, "outside"), (4, 0, 1, "blocks"), (0, 0, 1, "blocks")])
def test_invalid_instances(n: int, start: int, end: int, msg: str) -> None:
    with pytest.raises(PuzzleError, match=msg):
        validate_instance(n, start, end, 3, 3)


def _legal2() -> list[Move]:
    return solve_hanoi(2, 0, 2, 3, 3)  # (1: t0h1->t1h0), (0: t0h0->t2h0), (1: t1h0->t2h1)


@pytest.mark.parametrize(("moves", "msg"), [
    # a larger block on a smaller one
    ([Move(2, 0, 2, 1, 0), Move(1, 0, 1, 1, 1)], "smaller"),
    # a block that is not on top moves
    ([Move(0, 0, 0, 1, 0)], "top block"),
    # a block placed floating above an empty tower
    ([Move(1, 0, 1, 1, 1)], "none floats"),
    # wrong source height
    ([Move(1, 0, 0, 1, 0)], "height"),
    # same tower
    ([Move(1, 0, 1, 0, 1)], "same tower"),
    # tower outside the grid
    ([Move(1, 0, 1, 5, 0)], "outside"),
    # legal but incomplete
    (_legal2()[:2], "not all on tower"),
])
def test_checker_rejects(moves: list[Move], msg: str) -> None:
    n = 3 if moves[0].block == 2 or msg in ("smaller",) else 2
    with pytest.raises(PuzzleError, match=msg):
        check_sequence(moves, n, 0, 2, 3, 3)
