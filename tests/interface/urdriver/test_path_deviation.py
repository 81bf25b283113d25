"""ur3hanoi.interface.urdriver.path_deviation: the distance of executed suction points from the plan's path -- zero
on the plan, exact against a brute-force search over every piece, split by the plan's vertical legs."""

from __future__ import annotations

from dataclasses import replace
from functools import cache

import numpy as np
import pytest

from ur3hanoi.interface.urdriver.path_deviation import (
    PathDeviation,
    _point_piece_distances,
    path_deviation,
    plan_path,
    stretch_windows,
)
from ur3hanoi.interface.urdriver.plan_goals import plan_stretches
from ur3hanoi.plan import VERTICAL_PHASES, Phase, Plan, PlanConfig, plan_solve, sample, tcp_positions_world
from ur3hanoi.station.calibration import load_station


@cache
def plan() -> Plan:
    return plan_solve(load_station("lab_sim"), 0, 2, 1, PlanConfig())


def brute_force(p: Plan, q: np.ndarray) -> np.ndarray:
    """Each point's distance [m] from every piece of the path, the smallest."""
    path = plan_path(p)
    x = tcp_positions_world(p.station, q)
    out = np.empty(len(x))
    for i, xi in enumerate(x):
        out[i] = _point_piece_distances(np.broadcast_to(xi, path.a.shape), path.a, path.b).min()
    return out


def test_the_plans_own_samples_are_on_its_path() -> None:
    p = plan()
    d = path_deviation(p, p.trajectory.t, p.trajectory.q)
    assert d.max_m < 1e-6 and d.vertical_max_m is not None and d.vertical_max_m < 1e-6
    assert d.samples == len(p.trajectory.t)
    # Another rate of the exact plan (points between the pieces' ends): within the pieces' chord error.
    other = sample(p.segments, 333.0)
    assert path_deviation(p, other.t, other.q).max_m < 1e-6


def test_the_straight_pieces_stay_within_a_micrometre_of_the_plans_curve() -> None:
    p = plan()
    fine = sample(p.segments, 8000.0)
    assert path_deviation(p, fine.t, fine.q).max_m < 1e-6


def test_equals_a_brute_force_search_over_every_piece() -> None:
    p = plan()
    rng = np.random.default_rng(7)
    k = rng.choice(len(p.trajectory.t), size=150, replace=False)
    q = p.trajectory.q[k] + rng.normal(0.0, 3e-3, (len(k), 6))  # up to a few millimetres off
    expected = brute_force(p, q)
    d = path_deviation(p, p.trajectory.t[k], q)
    assert d.max_m == pytest.approx(expected.max(), abs=1e-12)
    assert d.max_m > 1e-3
    for i in rng.choice(len(k), size=10, replace=False):  # each point alone
        assert path_deviation(p, p.trajectory.t[k[i:i + 1]], q[i:i + 1]).max_m == pytest.approx(expected[i],
                                                                                               abs=1e-12)


def windows(p: Plan) -> np.ndarray:
    """Each plan sample's window: the stretch it belongs to (a dwell's own samples: its dwell)."""
    stretches = plan_stretches(p)
    label = np.zeros(len(p.trajectory.t), dtype=int)
    for i, s in enumerate(stretches):
        label[s.k0 + 1:s.k1 + 1] = i
    return stretch_windows(p, stretches)[label]


def test_each_sample_against_its_own_stretch() -> None:
    p = plan()
    tr = p.trajectory
    w = windows(p)
    assert path_deviation(p, tr.t, tr.q, w).max_m < 1e-6
    # The carry's samples measured against the first approach: far from it.
    stretches = plan_stretches(p)
    carry = next(s for s in stretches if s.carrying)
    k = np.arange(carry.k0, carry.k1 + 1)
    wrong = np.broadcast_to(stretch_windows(p, stretches)[0], (len(k), 2))
    assert path_deviation(p, tr.t[k], tr.q[k], wrong).max_m > 0.05
    assert path_deviation(p, tr.t[k], tr.q[k]).max_m < 1e-6  # against the whole path they are on it


def test_a_dwell_is_measured_against_the_motions_on_either_side() -> None:
    p = plan()
    stretches = plan_stretches(p)
    spans = stretch_windows(p, stretches)
    for i, s in enumerate(stretches):
        if s.kind == "motion":
            assert tuple(spans[i]) == (p.trajectory.t[s.k0], p.trajectory.t[s.k1])
        else:
            assert stretches[i - 1].kind == stretches[i + 1].kind == "motion"
            assert tuple(spans[i]) == (spans[i - 1][0], spans[i + 1][1])


def middles(mask: np.ndarray) -> np.ndarray:
    """The middle half of every run of ``mask``: away from where a carry and a vertical leg meet (the plan blends
    them inside the vertical corridor, so near the junction either is the nearest)."""
    out = np.zeros_like(mask)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    for a, b in zip(edges[::2], edges[1::2], strict=True):
        out[a + (b - a) // 4:b - (b - a) // 4] = True
    return out


@pytest.mark.parametrize("where", ["carry", "vertical"])
def test_the_vertical_legs_are_measured_apart(where: str) -> None:
    p = plan()
    tr = p.trajectory
    moved = middles(tr.phase == Phase.CARRY if where == "carry" else np.isin(tr.phase, [int(x) for x in
                                                                                       VERTICAL_PHASES]))
    q = tr.q.copy()
    # 10 mrad across the path: the shoulder in a carry (mostly a turn of the base), the base on a vertical leg.
    q[moved, 1 if where == "carry" else 0] += 0.01
    d = path_deviation(p, tr.t, q, windows(p))
    assert d.max_m > 2e-3 and d.vertical_max_m is not None
    if where == "carry":
        assert d.worst_phase == "CARRY" and d.vertical_max_m < 1e-6
    else:
        assert d.worst_phase in {Phase(x).name for x in VERTICAL_PHASES} and d.vertical_max_m == d.max_m
    assert np.min(np.abs(tr.t[moved] - tr.t[0] - d.worst_t_s)) < 1e-9  # the worst is one of the moved samples


def test_a_plan_without_segments_is_measured_against_its_samples() -> None:
    p = replace(plan(), segments=())
    assert path_deviation(p, p.trajectory.t, p.trajectory.q).max_m < 1e-9


def test_no_joint_states_is_an_error() -> None:
    with pytest.raises(ValueError, match="no joint states"):
        path_deviation(plan(), np.zeros(0), np.zeros((0, 6)))


def test_what_it_says() -> None:
    d = PathDeviation(4.1234e-4, 1.2e-4, "CARRY", 12.3456, 3451)
    assert d.describe() == "followed the plan within 0.41 mm (vertical legs 0.12 mm)"
    assert d.as_dict() == {"path_deviation_mm": 0.4123, "vertical_path_deviation_mm": 0.12,
                           "path_deviation_phase": "CARRY", "path_deviation_at_s": 12.346,
                           "joint_states_measured": 3451}
    assert replace(d, vertical_max_m=None).describe() == "followed the plan within 0.41 mm"
