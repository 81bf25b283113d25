"""Every accepted plan executes: plans on a tall grid run in MuJoCo and end with every block on the destination
tower, within the executor's final check (5 mm of its slot).

On a 10-level grid, 5 blocks used to end with the stack drifted 4.4-7.9 mm and 6 blocks with block 6 torn off in
move 23: resting stacks crept in the simulator and grasps kept the accumulated offset (see
:class:`ur3hanoi.sim.SceneConfig`). On the 8-level grid, 7 and 8 blocks then ended 8.1 mm off: placing onto tower
1's 2-block stack, the block touched down while still closing in on the vertical line, tilted the stack and was
thrown ~0.6 mm on release, 15 times over (:func:`ur3hanoi.plan.motion.vertical.place_band`). 8 blocks then still
ended 4.8 mm off, ~0.02 mm added at each of the top block's 128 moves, always the same way: the soft suction weld
let the block shift in the cup at every touch-down, friction 1.0 made a block touching down drag the stack below
instead of sliding, and the soft joint servo left the cup 0.02-0.03 mm off its pose when the suction switched
(:class:`ur3hanoi.sim.SceneConfig`, :data:`ur3hanoi.sim.model.DRIVES`). The tests hold every block within
:data:`MARGIN_M` of its slot, half the final check, so that a drift shows before it fails a solve.
``bench/bench_executes.py`` runs N = 1 .. height on every grid, 8 blocks on the 8-level grid among them (255 moves,
the top block moved 128 times: 1.15 mm off; 4.8 mm before the weld, friction and servo were corrected), which takes
two minutes of a core and is left to it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from ur3hanoi.plan import Plan, plan_solve
from ur3hanoi.plan.checks.vertical import check_vertical
from ur3hanoi.plan.motion import vertical
from ur3hanoi.plan.route import connections
from ur3hanoi.sim import run_plan
from ur3hanoi.sim.scene import slot_centers
from ur3hanoi.station.calibration import Station

MARGIN_M = 0.0025  # [m] half the executor's final check (SimConfig.place_tolerance_m, 5 mm)


def _tall(lab_real: Station, n_heights: int = 10) -> Station:
    """lab_real with ``n_heights`` levels, its towers pulled in so that the top levels stay reachable."""
    return dataclasses.replace(lab_real, n_heights=n_heights,
                               tower_origins=tuple((0.22, y, z) for _, y, z in lab_real.tower_origins))


def worst_offset_m(station: Station, n: int) -> float:
    """Solve N blocks tower 1 -> 3 in MuJoCo; the largest horizontal distance [m] of a final block from the centre
    of its slot (after checking that the run solved, every block in its slot)."""
    plan = plan_solve(station, 0, 2, n)
    result = run_plan(plan)
    assert result.status == "solved", result.error
    assert [(b.tower, b.height) for b in result.final_blocks] == [(2, b) for b in range(n)]
    centres = slot_centers(station)[2, :n, :2]
    xy = np.array([b.xyz[:2] for b in result.final_blocks])
    return float(np.max(np.linalg.norm(xy - centres, axis=1)))


# N blocks on a grid of L levels: `make test` runs one solve per grid, 6 blocks on the 10-level grid (63 moves,
# through move 23 where block 6 was torn off; its first half is the 5-block solve) and 5 on the 8-level grid (31
# moves, placing onto tower 1's 2-block stack among them). The others are marked `full` (`make test-all`);
# bench/bench_executes.py runs every N on every grid. The comments give the largest final offset measured.
TALL_GRID_SOLVES = [pytest.param(10, 6, marks=pytest.mark.slow, id="10-levels-6-blocks"),  # 0.41 mm
                    pytest.param(8, 5, id="8-levels-5-blocks"),  # 0.17 mm
                    pytest.param(10, 5, marks=pytest.mark.full, id="10-levels-5-blocks"),  # 0.17 mm
                    # 127 moves: ~60 s on one core (plan ~8 s, MuJoCo ~50 s)
                    pytest.param(8, 7, marks=[pytest.mark.slow, pytest.mark.full], id="8-levels-7-blocks")]  # 0.48 mm


@pytest.mark.parametrize(("levels", "n"), TALL_GRID_SOLVES)
def test_blocks_on_a_tall_grid_execute(lab_real: Station, levels: int, n: int) -> None:
    assert worst_offset_m(_tall(lab_real, levels), n) <= MARGIN_M


@pytest.fixture
def no_place_band(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> Iterator[float]:
    """The placing band switched off (any distance from the line allowed just above contact); yields the shipped
    tolerance. The cached station planners (they hold the legs built under the rule) are dropped before and after,
    and the user's cache is a private one: its keys hold the planner's source, not a patched constant."""
    shipped = vertical.PLACE_TOL_M
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    connections._cached_planner.cache_clear()
    monkeypatch.setattr(vertical, "PLACE_TOL_M", 1.0)
    yield shipped
    monkeypatch.undo()
    connections._cached_planner.cache_clear()


def _placed_on_tower_1(station: Station) -> tuple[float, Plan]:
    """3 blocks tower 3 -> 1 (the last move places the top block on tower 1's 2-block stack): the top block's
    final horizontal distance [m] from its slot in MuJoCo, and what the plan's vertical check (with the placing
    band in force) says about the plan."""
    plan = plan_solve(station, 2, 0, 3)
    result = run_plan(plan)
    assert result.status == "solved", result.error
    top = result.final_blocks[2]
    assert (top.tower, top.height) == (0, 2)
    off = float(np.linalg.norm(np.asarray(top.xyz[:2]) - slot_centers(station)[0, 2, :2]))
    return off, plan


def test_placing_onto_a_stack_close_to_the_line_leaves_the_block_in_place(lab_real: Station) -> None:
    tall = _tall(lab_real, 8)
    off, plan = _placed_on_tower_1(tall)
    assert off < 0.0003  # measured 0.05 mm
    assert check_vertical(plan.trajectory, plan.moves, tall, 0.002)[0] == []


def test_a_block_touching_down_off_the_line_stays_in_place(lab_real: Station, no_place_band: float) -> None:
    """Without the placing band the same placement touches down ~0.7 mm off the line, still closing in on it (the
    plan's own check, with the band, refuses it). With a soft suction weld, friction 1.0 and no acceleration
    feed-forward the carried block dragged the stack's top, tilted the stack and, released, was thrown 0.68 mm off
    its slot; now it ends 0.01 mm off (measured). Each correction matters: friction 1.0 alone gives 0.15 mm, the
    0.01 s weld 0.27 mm, no acceleration feed-forward 0.31 mm (measured; :class:`ur3hanoi.sim.SceneConfig`,
    :class:`ur3hanoi.sim.SimConfig`)."""
    tall = _tall(lab_real, 8)
    off, plan = _placed_on_tower_1(tall)
    assert off < 0.0001
    assert check_vertical(plan.trajectory, plan.moves, tall, 0.002)[0] == []  # the 2 mm corridor alone passes it
    vertical.PLACE_TOL_M = no_place_band  # restored by the fixture's monkeypatch
    assert check_vertical(plan.trajectory, plan.moves, tall, 0.002)[0] != []
