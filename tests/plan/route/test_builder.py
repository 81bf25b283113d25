"""The segment builder (ur3hanoi.plan.route.builder): chained segments, the hops, rising over taller towers."""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
import pytest

from ur3hanoi.hanoi import Move, solve_hanoi, stacks_before_moves
from ur3hanoi.plan import Phase, PlanConfig, Segment
from ur3hanoi.plan.route.builder import OVER_MARGIN_M, SegmentBuilder, plan_hops
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import block_center_world, contact_point_world


def _build(station: Station, start: int, end: int, n: int,
           config: PlanConfig) -> tuple[SegmentBuilder, list[Move], list[Segment]]:
    b = SegmentBuilder(station, config)
    moves = solve_hanoi(n, start, end, station.n_towers, station.n_heights)
    return b, moves, b.build(plan_hops(station, moves, n, start, config.clearance_m))


@pytest.mark.parametrize("pass_through", [True, False])
def test_segments_are_chained(lab_real: Station, pass_through: bool) -> None:
    """Each segment starts when and where the previous one ended, from home back to home, at rest at both ends."""
    b, _, segs = _build(lab_real, 0, 2, 3, PlanConfig(pass_through=pass_through))
    q_home = b.q_above(None)
    np.testing.assert_array_equal(segs[0].q_start, q_home)
    np.testing.assert_array_equal(segs[-1].q_end, q_home)
    assert segs[0].t_start == 0.0 and not np.any(segs[0].v_start) and not np.any(segs[-1].v_end)
    for a, c in itertools.pairwise(segs):
        assert c.t_start == a.t_end
        np.testing.assert_array_equal(c.q_start, a.q_end)
        np.testing.assert_array_equal(c.v_start, a.v_end)
    vias = [np.linalg.norm(s.v_end) for s in segs if s.phase in (Phase.TRANSIT, Phase.CARRY)]
    assert (max(vias) > 0.1) if pass_through else (max(vias) == 0.0)


def test_hops_from_home_to_home(lab_sim: Station) -> None:
    moves = solve_hanoi(2, 0, 2, 3, 3)
    hops = plan_hops(lab_sim, moves, 2, 0, 0.005)
    assert len(hops) == 2 * len(moves) + 1
    assert hops[0].slot0 is None and hops[-1].slot1 is None
    for m, a, b in zip(moves, hops[0:-1:2], hops[1:-1:2], strict=True):
        assert a.slot1 == b.slot0 == (m.from_tower, m.from_height) and b.slot1 == (m.to_tower, m.to_height)
        assert a.dwell_step == (Phase.GRASP_DWELL, moves.index(m)) and b.across_step[0] == Phase.CARRY
    assert all(h.over0 is None and h.over1 is None for h in hops)  # the lab towers never need it


def test_tall_towers_are_cleared(lab_real: Station) -> None:
    """On a 10-level grid the carried block rises over every taller stack between its two towers: the over
    height leaves the clearance plus the margin under the carried block (or the cup)."""
    tall = dataclasses.replace(lab_real, n_heights=10,
                               tower_origins=tuple((0.22, y, z) for _, y, z in lab_real.tower_origins))
    n = 8
    moves = solve_hanoi(n, 0, 2, 3, 10)
    hops = plan_hops(tall, moves, n, 0, 0.005)
    stacks = stacks_before_moves(moves, n, 0, 3)
    risen = 0
    for k, hop in enumerate(hops[:-1]):
        if hop.slot0 is None or hop.slot1 is None or (hop.over0 is None and hop.over1 is None):
            continue
        risen += 1
        mi = k // 2
        carrying = hop.across_step[0] == Phase.CARRY
        towers = [list(t) for t in stacks[mi]]
        if carrying:
            towers[moves[mi].from_tower].pop()
        lo, hi = sorted((hop.slot0[0], hop.slot1[0]))
        top = max(block_center_world(tall, t, h)[2] + tall.block_size / 2
                  for t in range(lo, hi + 1) for h in range(len(towers[t])))
        hang = tall.block_size - tall.contact_depth if carrying else 0.0
        over = hop.over0 if hop.over0 is not None else hop.over1
        assert over is not None and over - hang >= top + 0.005 + OVER_MARGIN_M - 1e-12
        for slot, z in ((hop.slot0, hop.over0), (hop.slot1, hop.over1)):
            if z is not None:
                assert z > contact_point_world(tall, *slot)[2] + tall.approach
    assert risen > 10
