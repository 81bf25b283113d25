"""Ruckig motion plans: limits, endpoints, vertical approach, pass-through vs stop-and-go, clearances, CLI."""

from __future__ import annotations

import csv
import dataclasses
import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ur3hanoi.cli import main
from ur3hanoi.errors import PlanError, PuzzleError
from ur3hanoi.grid import ABOVE, ON
from ur3hanoi.plan import Phase, Plan, PlanConfig, build_waypoints, check_vertical, plan_solve
from ur3hanoi.resources import stations_dir
from ur3hanoi.station import Station, load_station

ROOT = Path(__file__).resolve().parents[1]
STATIONS = {name: stations_dir() / f"{name}.yaml" for name in ("lab_sim", "lab_real")}
PAIRS = list(itertools.permutations(range(3), 2))


@pytest.fixture(scope="module")
def stations() -> dict[str, Station]:
    return {name: load_station(path) for name, path in STATIONS.items()}


@pytest.fixture(scope="module")
def plans(stations: dict[str, Station]) -> dict[tuple[str, int, int, int], Plan]:
    """Every start/end pair for N = 1..3 on both stations, planned once (with clearance checks)."""
    return {(name, s, e, n): plan_solve(st_, s, e, n, PlanConfig())
            for name, st_ in stations.items() for s, e in PAIRS for n in (1, 2, 3)}


def _assert_limits(plan: Plan) -> None:
    tr, lim = plan.trajectory, plan.limits
    assert lim is not None
    for arr, m in ((tr.qd, lim.v_max), (tr.qdd, lim.a_max), (tr.qddd, lim.j_max)):
        assert np.all(np.abs(arr) <= m * (1 + 1e-6))
    assert np.all(tr.q >= np.asarray(plan.station.limits.q_min)) and np.all(tr.q <= plan.station.limits.q_max)


def test_all_pairs_plan_cleanly(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    assert len(plans) == 36
    for (_, _, _, n), plan in plans.items():
        assert len(plan.moves) == 2**n - 1
        assert plan.violations == ()
        _assert_limits(plan)


def test_velocity_limits_are_the_datasheet(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    plan = plans[("lab_sim", 0, 2, 3)]
    assert plan.limits is not None
    np.testing.assert_allclose(plan.limits.v_max, [np.pi] * 3 + [2 * np.pi] * 3)


def test_endpoints_reached(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    for (name, _, _, _), plan in plans.items():
        wp = build_waypoints(plan.station)
        tr = plan.trajectory
        np.testing.assert_allclose(tr.q[0], wp.q_home, atol=1e-6)
        np.testing.assert_allclose(tr.q[-1], wp.q_home, atol=1e-6)
        assert not tr.suction[-1]
        for seg in plan.segments:
            if seg.trajectory is None:
                continue
            end = seg.trajectory.at_time(seg.duration)[0]
            q_end = seg.path.evaluate(end[0])[0] if seg.path is not None else np.array(end)
            np.testing.assert_allclose(q_end, seg.q_end, atol=1e-6, err_msg=f"{name} {seg.target}")
        # Every move's on/above poses are the table's entries.
        for i, m in enumerate(plan.moves):
            segs = [s for s in plan.segments if s.move_index == i]
            ph = {s.phase: s for s in segs}
            np.testing.assert_allclose(ph[Phase.GRASP_DWELL].q_start, wp.table[m.from_tower, m.from_height, ON])
            np.testing.assert_allclose(ph[Phase.TRANSIT].q_end, wp.table[m.from_tower, m.from_height, ABOVE])
            np.testing.assert_allclose(ph[Phase.RELEASE_DWELL].q_start, wp.table[m.to_tower, m.to_height, ON])
            np.testing.assert_allclose(ph[Phase.CARRY].q_end, wp.table[m.to_tower, m.to_height, ABOVE])


def test_dwell_samples_rest_on_contact(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    plan = plans[("lab_real", 1, 0, 3)]
    tr = plan.trajectory
    for ph in (Phase.GRASP_DWELL, Phase.RELEASE_DWELL):
        idx = tr.phase == int(ph)
        assert np.all(tr.qd[idx] == 0.0)
    assert np.all(tr.suction[tr.phase == int(Phase.CARRY)])
    assert not np.any(tr.suction[tr.phase == int(Phase.TRANSIT)])


def test_pass_through_beats_stop_and_go(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    for plan in plans.values():
        assert plan.duration_s <= plan.stop_and_go_duration_s + 1e-9
    lab = plans[("lab_sim", 0, 2, 3)]
    assert lab.motion_saving >= 0.15
    # No stop at a pass-through above point: the via velocity into each descend is non-zero.
    descends = [s for s in lab.segments if s.phase == Phase.DESCEND_PICK]
    assert any(np.linalg.norm(s.v_start) > 0.1 for s in descends)


def test_vertical_approach_within_2mm(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    for plan in plans.values():
        viol, worst = check_vertical(plan.trajectory, plan.moves, plan.station, 0.002)
        assert viol == [] and worst < 0.002


def test_tall_grid_all_heights(stations: dict[str, Station]) -> None:
    tall = dataclasses.replace(stations["lab_real"], n_heights=5)
    plan = plan_solve(tall, 0, 2, 5, PlanConfig(check_collisions=False))
    assert len(plan.moves) == 31 and plan.violations == ()


def test_puzzle_errors(stations: dict[str, Station]) -> None:
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 1, 1, 2)
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 0, 1, 4)
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 0, 3, 2)


def test_clearance_check_detects(stations: dict[str, Station]) -> None:
    """An impossible 20 cm block clearance must be reported (the check is live)."""
    cfg = PlanConfig(clearance_m=0.2, raise_on_violation=False)
    plan = plan_solve(stations["lab_real"], 0, 2, 2, cfg)
    assert any("carried_block" in v for v in plan.violations)
    with pytest.raises(PlanError, match="carried_block"):
        plan_solve(stations["lab_real"], 0, 2, 2, dataclasses.replace(cfg, raise_on_violation=True))


def test_rate_500(stations: dict[str, Station]) -> None:
    plan = plan_solve(stations["lab_sim"], 0, 1, 2, PlanConfig(rate_hz=500, check_collisions=False))
    np.testing.assert_allclose(np.diff(plan.trajectory.t), 1 / 500)
    _assert_limits(plan)


@settings(max_examples=6, deadline=None)
@given(speed=st.floats(0.2, 1.0), shift=st.tuples(st.floats(-0.03, 0.03), st.floats(-0.03, 0.03)),
       pair=st.sampled_from(PAIRS))
def test_limits_property(speed: float, shift: tuple[float, float], pair: tuple[int, int]) -> None:
    base = load_station(STATIONS["lab_real"])
    moved = base.with_grid([(x + shift[0], y + shift[1], z) for x, y, z in base.tower_origins], base.height_step,
                           base.tool_yaw)
    plan = plan_solve(moved, pair[0], pair[1], 2, PlanConfig(speed=speed, check_collisions=False))
    _assert_limits(plan)
    assert plan.duration_s <= plan.stop_and_go_duration_s + 1e-9


# ----------------------------------------------------------------------------------------------------------- CLI


def test_cli_exit_codes(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--start", "1", "--end", "1", "--calibration", str(STATIONS["lab_sim"])]) == 2
    assert "error" in capsys.readouterr().err
    assert main(["plan", "--start", "1", "--end", "2", "--blocks", "4", "--calibration",
                 str(STATIONS["lab_sim"])]) == 2


def test_cli_json_and_csv(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "plan.csv"
    rc = main(["plan", "--start", "1", "--end", "3", "--blocks", "2", "--calibration", str(STATIONS["lab_sim"]),
               "--csv", str(out), "--json"])
    assert rc == 0
    data = json.loads(capsys.readouterr().out)
    for key in ("moves", "duration_s", "stop_and_go_duration_s", "rate_hz", "max_abs_velocity",
                "max_abs_acceleration", "max_abs_jerk", "velocity_limit", "acceleration_limit", "jerk_limit",
                "violations"):
        assert key in data
    assert data["moves"][0] == {"block": 2, "from_tower": 1, "from_height": 2, "to_tower": 2, "to_height": 1}
    assert data["violations"] == [] and len(data["max_abs_jerk"]) == 6
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction"]
    assert {r[-1] for r in rows[1:]} == {"0", "1"}


# ------------------------------------------------------------------------------------------------- sampling


def test_sampling_matches_ruckig_at_time(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    """The vectorized sampler equals Ruckig's own at_time (joints) / at_time + path map (vertical legs)."""
    plan = plans[("lab_real", 0, 2, 3)]
    tr = plan.trajectory
    rng = np.random.default_rng(0)
    for k in rng.choice(len(tr.t) - 1, 300, replace=False):
        seg = next(s for s in reversed(plan.segments) if s.t_start <= tr.t[k])
        if seg.trajectory is None:
            np.testing.assert_array_equal(tr.q[k], seg.q_start)
            continue
        x, xd, xdd = (np.array(v) for v in seg.trajectory.at_time(min(tr.t[k] - seg.t_start, seg.duration)))
        if seg.path is not None:
            q, d1, d2, _ = seg.path.evaluate(x[0])
            x, xd, xdd = q, d1 * xd[0], d2 * xd[0] ** 2 + d1 * xdd[0]
        np.testing.assert_allclose(tr.q[k], x, rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.qd[k], xd, rtol=0, atol=1e-12)
        np.testing.assert_allclose(tr.qdd[k], xdd, rtol=0, atol=1e-11)


def test_sampling_brake_profile_fallback() -> None:
    """A start above the velocity limit gives Ruckig a brake pre-profile; sampling still equals at_time."""
    from ruckig import InputParameter, Ruckig
    from ruckig import Trajectory as RuckigTrajectory

    from ur3hanoi.plan import Segment, sample

    inp = InputParameter(6)
    inp.current_position, inp.target_position = [0.0] * 6, [0.5, -0.3, 0.2, 0.1, 0.0, -0.4]
    inp.current_velocity = [1.5, 0.0, 0.0, 0.0, 0.0, 0.0]  # above max_velocity: brake first
    inp.max_velocity, inp.max_acceleration, inp.max_jerk = [1.0] * 6, [2.0] * 6, [10.0] * 6
    traj = RuckigTrajectory(6)
    Ruckig(6).calculate(inp, traj)
    assert traj.profiles[0][0].brake.duration > 0
    z = np.zeros(6)
    seg = Segment(Phase.TRANSIT, 0, 0.0, traj.duration, z, np.array(inp.target_position), z, z, "x", traj)
    tr = sample([seg], 125.0)
    for k in range(len(tr.t) - 1):
        x, xd, xdd = (np.array(v) for v in traj.at_time(tr.t[k]))
        np.testing.assert_array_equal(tr.q[k], x)
        np.testing.assert_array_equal(tr.qd[k], xd)
        np.testing.assert_array_equal(tr.qdd[k], xdd)


def test_batched_fk_matches_pinocchio(stations: dict[str, Station]) -> None:
    from ur3hanoi.plan import _tcp_positions_world
    from ur3hanoi.robot import load_ur3

    st_ = stations["lab_real"]
    robot = load_ur3(st_.tool, st_.limits)
    q = np.random.default_rng(1).uniform(-3.0, 3.0, (50, 6))
    expected = np.array([(st_.T_world_base * robot.fk(qi, "tcp")).translation for qi in q])
    np.testing.assert_allclose(_tcp_positions_world(st_, q), expected, rtol=0, atol=1e-10)


def test_via_descent_finds_grid_optimum(stations: dict[str, Station]) -> None:
    """The descent over via-speed candidates picks the optimum of the full candidate grid on every connection."""
    from ur3hanoi.hanoi import solve_hanoi
    from ur3hanoi.plan import _AT_REST, _Builder

    for name, (s, e) in itertools.product(STATIONS, [(0, 2), (2, 1)]):
        st_ = stations[name]
        b = _Builder(st_, build_waypoints(st_), PlanConfig())
        b.build(solve_hanoi(3, s, e, st_.n_towers, st_.n_heights))
        for (slot0, q0b, slot1, q1b), (s0, s1, traj) in b._horizontal_memo.items():
            q0, q1 = np.frombuffer(q0b), np.frombuffer(q1b)
            c0 = b.legs(slot0) if slot0 is not None else _AT_REST
            c1 = b.legs(slot1) if slot1 is not None else _AT_REST
            legs0 = [c0.get(i) for i in range(c0.count())]
            legs1 = [c1.get(j) for j in range(c1.count())]
            chosen = next(l0.duration for l0 in legs0 if l0 and l0.sigma == s0) + traj.duration + next(
                l1.duration for l1 in legs1 if l1 and l1.sigma == s1)
            best = np.inf
            for l0, l1 in itertools.product(legs0, legs1):
                assert l0 is not None and l1 is not None
                t = b.rk.calc(q0, *b.via_state(slot0, l0.sigma, False), q1, *b.via_state(slot1, l1.sigma, True))
                if t is not None:
                    best = min(best, l0.duration + t.duration + l1.duration)
            assert chosen == pytest.approx(best, abs=1e-12)


@pytest.mark.parametrize("field", ["collision_rate_hz", "vertical_tol_m", "clearance_m"])
@pytest.mark.parametrize("value", [float("nan"), 0.0, -1.0, float("inf")])
def test_config_rejects_non_finite_or_non_positive(field: str, value: float) -> None:
    with pytest.raises(PlanError, match=field):
        dataclasses.replace(PlanConfig(), **{field: value}).validate()
