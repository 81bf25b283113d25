"""Export (ur3hanoi.plan.export): the CSV round-trips the samples exactly; the JSON summary is 1-based and complete."""

from __future__ import annotations

import csv
import io
import itertools
import json

import numpy as np
import pytest

from ur3hanoi.plan import Phase, Plan, PlanConfig, plan_json_dict, plan_solve, trajectory_csv
from ur3hanoi.station.calibration import Station


@pytest.fixture(scope="module")
def plan(lab_sim: Station) -> Plan:
    return plan_solve(lab_sim, 1, 2, 2, PlanConfig(check_collisions=False))


def test_csv_round_trips_every_sample(plan: Plan) -> None:
    tr = plan.trajectory
    rows = list(csv.reader(io.StringIO(trajectory_csv(tr))))
    assert rows[0] == ["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction", "move",
                       "phase"]
    np.testing.assert_array_equal([int(r[14]) for r in rows[1:]], tr.move_index + 1)
    assert [r[15] for r in rows[1:]] == [Phase(int(p)).name for p in tr.phase]
    data = np.array([r[:14] for r in rows[1:]], dtype=float)
    assert data.shape == (len(tr.t), 14)
    np.testing.assert_allclose(data[:, 0], tr.t, rtol=0, atol=5e-7)  # t is printed with 6 decimals
    np.testing.assert_array_equal(data[:, 1:7], tr.q)  # repr round-trips float64 exactly
    np.testing.assert_array_equal(data[:, 7:13], tr.qd)
    np.testing.assert_array_equal(data[:, 13], tr.suction.astype(float))


def test_json_summary(plan: Plan) -> None:
    d = json.loads(json.dumps(plan_json_dict(plan)))
    assert (d["start_tower"], d["end_tower"], d["blocks"]) == (2, 3, 2)
    assert d["moves"][0] == {"block": 2, "from_tower": 2, "from_height": 2, "to_tower": 1, "to_height": 1}
    assert d["samples"] == len(plan.trajectory.t) and d["rate_hz"] == 125.0
    assert d["duration_s"] == plan.duration_s
    assert d["motion_s"] == pytest.approx(plan.duration_s - 6 * 0.3)  # 3 moves, 2 dwells of 0.3 s each
    assert plan.limits is not None
    np.testing.assert_array_equal(d["velocity_limit"], plan.limits.v_max)
    assert np.all(np.array(d["max_abs_velocity"]) <= plan.limits.v_max * (1 + 1e-6))
    assert d["violations"] == [] and set(d["planning_time_s"]) >= {"build", "ruckig", "sampling", "checks"}
    assert d["stop_and_go_duration_s"] == plan.stop_and_go_duration_s
    assert d["exact_vertical_stop_and_go_duration_s"] > d["stop_and_go_duration_s"] > d["duration_s"]
    assert d["motion_ratio"] == pytest.approx(plan.motion_s / plan.stop_and_go_motion_s)
    assert 0 < d["max_vertical_deviation_m"] <= 0.002


def test_json_move_times(plan: Plan) -> None:
    """Each move from the end of the previous one to the end of its release dwell, with its waypoints in order;
    the way home is move 0 and ends with the plan."""
    times = plan_json_dict(plan)["move_times"]
    assert [m["move"] for m in times] == [1, 2, 3, 0]
    assert times[0]["start_s"] == 0.0 and times[-1]["end_s"] == pytest.approx(plan.duration_s)
    for a, b in itertools.pairwise(times):
        assert a["end_s"] == pytest.approx(b["start_s"])
    for i, m in enumerate(plan.moves):
        d = m.as_lab_dict()
        poses = [(w["pose"], w["tower"], w["height"]) for w in times[i]["waypoints"]]
        src, dst = (d["from_tower"], d["from_height"]), (d["to_tower"], d["to_height"])
        assert poses[-4:] == [("on", *src), ("above", *src), ("above", *dst), ("on", *dst)]
        ts = [w["t_s"] for w in times[i]["waypoints"]]
        assert ts == sorted(ts) and times[i]["start_s"] < ts[0] and ts[-1] < times[i]["end_s"]
    assert times[-1]["waypoints"][-1]["pose"] == "home"
