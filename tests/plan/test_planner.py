"""Planning a solve (ur3hanoi.plan.planner): limits, endpoints, vertical approach, pass-through vs stop-and-go, CLI.

The modules of the plan subpackage have their own test files (tests/test_plan_<module>.py)."""

from __future__ import annotations

import csv
import dataclasses
import itertools
import json
from pathlib import Path

import numpy as np
import pytest
from hypothesis import example, given, reject, settings
from hypothesis import strategies as st

from tests.support import REPO
from ur3hanoi.cli import main
from ur3hanoi.errors import IKError, PlanError, PuzzleError
from ur3hanoi.io.resources import stations_dir
from ur3hanoi.plan import Phase, Plan, PlanConfig, build_waypoints, check_collisions, check_vertical, plan_solve
from ur3hanoi.plan.baseline.lab_program import lab_program_times
from ur3hanoi.plan.motion.corridor import DENSE_MARGIN_M
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, ON

ROOT = REPO
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


def test_faster_than_the_lab_program_and_stop_and_go(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    """Every plan beats joint-space stop-and-go between the same waypoints; the 3-block lab solves move at most
    0.80 x as long as the lab program itself (movej per waypoint at v = a = 4), under the same speed and
    acceleration caps."""
    for plan in plans.values():
        assert plan.motion_s < plan.stop_and_go_motion_s
    for name in STATIONS:
        plan = plans[(name, 0, 2, 3)]
        assert plan.motion_s <= 0.80 * lab_program_times(plan.station, plan.moves).motion_s
    # No stop at a pass-through above point: the via velocity into each descend is non-zero.
    descends = [s for s in plans[("lab_sim", 0, 2, 3)].segments if s.phase == Phase.DESCEND_PICK]
    assert all(np.linalg.norm(s.v_start) > 0.1 for s in descends if s.target.startswith("via"))


def test_vertical_approach_within_2mm(plans: dict[tuple[str, int, int, int], Plan]) -> None:
    for plan in plans.values():
        viol, worst = check_vertical(plan.trajectory, plan.moves, plan.station, 0.002)
        assert viol == [] and worst < 0.002


def test_tall_grid_plans_every_n(stations: dict[str, Station]) -> None:
    """A 10-level grid (towers pulled in so the top levels are reachable) plans 1..10 blocks with every check,
    clearances included: the carried block rises over taller towers (it hit block_6 from 8 blocks up before).
    Faster than the stop-and-go between the same waypoints from 2 blocks on; the single move of 1 block may take up
    to 5 % longer: its slots next to the base need the many-point legs that keep the vertical line without dipping
    into the stack (see ur3hanoi.plan.motion.legs.CONTACT_OVERSHOOT_M), which the stop-and-go ignores."""
    real = stations["lab_real"]
    tall = dataclasses.replace(real, n_heights=10, tower_origins=tuple((0.22, y, z) for _, y, z in real.tower_origins))
    for n in range(1, 11):
        plan = plan_solve(tall, 0, 2, n)
        assert len(plan.moves) == 2**n - 1 and plan.violations == ()
        assert plan.motion_s <= (1.05 if n == 1 else 1.0) * plan.stop_and_go_motion_s
        if n >= 8:
            assert any(s.target.startswith("over") for s in plan.segments)


def test_puzzle_errors(stations: dict[str, Station]) -> None:
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 1, 1, 2)
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 0, 1, 4)
    with pytest.raises(PuzzleError):
        plan_solve(stations["lab_sim"], 0, 3, 2)


def test_rate_500(stations: dict[str, Station]) -> None:
    plan = plan_solve(stations["lab_sim"], 0, 1, 2, PlanConfig(rate_hz=500, check_collisions=False))
    np.testing.assert_allclose(np.diff(plan.trajectory.t), 1 / 500)
    _assert_limits(plan)


@settings(max_examples=6, deadline=None, derandomize=True)
@example(name="lab_sim", speed=1.0, shift=(0.03125, 0.0), yaw=0.0, pair=(0, 1))  # the line slow near the reach
@example(name="lab_sim", speed=1.0, shift=(0.03125, 0.0390625), yaw=0.0, pair=(0, 1))  # tower 3 out of reach
@given(name=st.sampled_from(sorted(STATIONS)), speed=st.floats(0.2, 1.0),
       shift=st.tuples(st.floats(-0.04, 0.04), st.floats(-0.04, 0.04)), yaw=st.floats(-0.3, 0.3),
       pair=st.sampled_from(PAIRS))
def test_never_slower_than_the_honest_baseline(name: str, speed: float, shift: tuple[float, float], yaw: float,
                                               pair: tuple[int, int]) -> None:
    """Random stations (the lab grids moved and turned) and speeds: within the limits, on the vertical line, and
    never slower than stop-and-go that keeps the same vertical line. (The joint-space stop-and-go, which leaves the
    line by 3-10 mm, is beaten on the shipped stations, test_faster_than_the_lab_program_and_stop_and_go; a grid
    moved towards the edge of the reach makes the line itself slow, e.g. lab_sim moved 31 mm along x: 11.27 s
    against 10.61 s joint-space and 15.69 s on the line.) A grid moved out of reach is refused, not planned."""
    base = load_station(STATIONS[name])
    moved = base.with_grid([(x + shift[0], y + shift[1], z) for x, y, z in base.tower_origins], base.height_step,
                           base.tool_yaw + yaw)
    try:
        plan = plan_solve(moved, pair[0], pair[1], 2, PlanConfig(speed=speed, check_collisions=False))
    except (PlanError, IKError) as exc:
        assert "no IK solution" in str(exc) or "unreachable" in str(exc), exc
        reject()
    _assert_limits(plan)
    assert plan.vertical_deviation_m <= 0.002
    assert plan.motion_s <= plan.exact_vertical_stop_and_go_motion_s


def test_limits_line_and_clearances_hold_at_1khz(stations: dict[str, Station]) -> None:
    """Sampled at 1 kHz: every sample within the limits and within 2 mm of the vertical line, and the clearances
    (the segment check resolves to 1 ms; the sample-based check agrees at 1 kHz)."""
    for st_ in stations.values():
        plan = plan_solve(st_, 0, 2, 3, PlanConfig(rate_hz=1000.0))
        np.testing.assert_allclose(np.diff(plan.trajectory.t), 1e-3)
        _assert_limits(plan)
        viol, worst = check_vertical(plan.trajectory, plan.moves, st_, 0.002)
        # Other sample times than the legs' own 1 kHz check: within its margin of what it measured.
        assert viol == [] and worst <= plan.vertical_deviation_m + DENSE_MARGIN_M
        assert plan.vertical_deviation_m <= 0.002 - DENSE_MARGIN_M
        assert plan.limits is not None
        assert check_collisions(plan.trajectory, plan.moves, st_, plan.n_blocks, plan.start, plan.config,
                                plan.limits) == []


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
    for key in ("moves", "duration_s", "stop_and_go_duration_s", "exact_vertical_stop_and_go_duration_s", "rate_hz",
                "max_abs_velocity", "max_abs_acceleration", "max_abs_jerk", "velocity_limit", "acceleration_limit",
                "jerk_limit", "violations", "move_times"):
        assert key in data
    assert data["moves"][0] == {"block": 2, "from_tower": 1, "from_height": 2, "to_tower": 2, "to_height": 1}
    assert data["violations"] == [] and len(data["max_abs_jerk"]) == 6
    with out.open() as f:
        rows = list(csv.reader(f))
    assert rows[0] == ["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction", "move",
                       "phase"]
    assert {r[13] for r in rows[1:]} == {"0", "1"} and {r[14] for r in rows[1:]} == {"0", "1", "2", "3"}


@pytest.mark.parametrize("field", ["collision_rate_hz", "vertical_tol_m", "clearance_m"])
@pytest.mark.parametrize("value", [float("nan"), 0.0, -1.0, float("inf")])
def test_config_rejects_non_finite_or_non_positive(field: str, value: float) -> None:
    with pytest.raises(PlanError, match=field):
        dataclasses.replace(PlanConfig(), **{field: value}).validate()


@pytest.mark.parametrize(("field", "value"), [("via_speeds", (0.5, 1.0)), ("via_speeds", (0.0, -1.0)),
                                              ("via_speeds", (0.0, 2.0, 1.0)), ("via_accels", (1.0, 2.0)),
                                              ("via_accels", (0.0, float("nan")))])
def test_config_rejects_a_bad_via_grid(field: str, value: tuple[float, ...]) -> None:
    """The grid must hold 0 (the rest-to-rest fallback) and increase (the search steps to neighbours)."""
    with pytest.raises(PlanError, match=field):
        dataclasses.replace(PlanConfig(), **{field: value}).validate()
