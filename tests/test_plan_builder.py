"""The segment builder (ur3hanoi.plan.builder): chained segments, and the via speeds it picks are the grid optimum."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from ur3hanoi.hanoi import Move, solve_hanoi
from ur3hanoi.plan import OfflineRuckig, Phase, PlanConfig, Segment, build_waypoints
from ur3hanoi.plan.builder import SegmentBuilder
from ur3hanoi.station import Station

HORIZONTAL = (Phase.TRANSIT, Phase.CARRY, Phase.HOME)
Slot = tuple[int, int]


def _build(station: Station, start: int, end: int, n: int,
           config: PlanConfig) -> tuple[SegmentBuilder, list[Move], list[Segment]]:
    b = SegmentBuilder(station, build_waypoints(station), config)
    moves = solve_hanoi(n, start, end, station.n_towers, station.n_heights)
    return b, moves, b.build(moves)


@pytest.mark.parametrize("pass_through", [True, False])
def test_segments_are_chained(lab_real: Station, pass_through: bool) -> None:
    """Each segment starts when and where the previous one ended, from home back to home, at rest at both ends."""
    b, _, segs = _build(lab_real, 0, 2, 3, PlanConfig(pass_through=pass_through))
    q_home = b.wp.q_home
    np.testing.assert_array_equal(segs[0].q_start, q_home)
    np.testing.assert_array_equal(segs[-1].q_end, q_home)
    assert segs[0].t_start == 0.0 and not np.any(segs[0].v_start) and not np.any(segs[-1].v_end)
    for a, c in itertools.pairwise(segs):
        assert c.t_start == a.t_end
        np.testing.assert_array_equal(c.q_start, a.q_end)
        np.testing.assert_array_equal(c.v_start, a.v_end)
    vias = [np.linalg.norm(s.v_end) for s in segs if s.phase in (Phase.TRANSIT, Phase.CARRY)]
    assert (max(vias) > 0.1) if pass_through else (max(vias) == 0.0)


def _leg_options(b: SegmentBuilder, slot: Slot | None) -> list[tuple[float, float]]:
    """(sigma, duration) of every feasible candidate of a slot's vertical leg; home: at rest, no leg."""
    if slot is None:
        return [(0.0, 0.0)]
    legs = b.legs(slot)
    out = []
    for i in range(legs.count()):
        leg = legs.get(i)
        assert leg is not None
        out.append((leg.sigma, leg.duration))
    return out


@pytest.mark.parametrize(("start", "end"), [(0, 2), (2, 1)])
def test_via_speeds_are_the_optimum_of_the_full_candidate_grid(shipped_station: Station, start: int,
                                                               end: int) -> None:
    """On every horizontal connection, exit leg + connection + entry leg is the least over all candidate pairs."""
    st_ = shipped_station
    b, moves, segs = _build(st_, start, end, 3, PlanConfig())
    lim = b.limits
    rk = OfflineRuckig(lim.v_max, lim.a_max, lim.j_max)
    # The slots each horizontal segment leaves and enters (None: home), in order.
    hops: list[tuple[Slot | None, Slot | None]] = []
    prev: Slot | None = None
    for m in moves:
        src, dst = (m.from_tower, m.from_height), (m.to_tower, m.to_height)
        hops += [(prev, src), (src, dst)]
        prev = dst
    hops.append((prev, None))
    horizontal = [k for k, s in enumerate(segs) if s.phase in HORIZONTAL]
    assert len(horizontal) == len(hops) == 2 * len(moves) + 1
    for k, (slot0, slot1) in zip(horizontal, hops, strict=True):
        seg = segs[k]
        exit_s = segs[k - 1].duration if slot0 is not None else 0.0
        entry_s = segs[k + 1].duration if slot1 is not None else 0.0
        chosen = exit_s + seg.duration + entry_s
        best = np.inf
        for (s0, d0), (s1, d1) in itertools.product(_leg_options(b, slot0), _leg_options(b, slot1)):
            sol = rk.solve(seg.q_start, *b.via_state(slot0, s0, down=False), seg.q_end,
                           *b.via_state(slot1, s1, down=True))
            if sol.trajectory is not None:
                best = min(best, d0 + sol.trajectory.duration + d1)
        assert chosen == pytest.approx(best, abs=1e-12), seg.target
