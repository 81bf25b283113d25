"""Export (ur3hanoi.plan.export): the CSV round-trips the samples exactly; the JSON summary is 1-based and complete."""

from __future__ import annotations

import csv
import io
import json

import numpy as np
import pytest

from ur3hanoi.plan import Plan, PlanConfig, plan_solve, trajectory_csv
from ur3hanoi.station import Station


@pytest.fixture(scope="module")
def plan(lab_sim: Station) -> Plan:
    return plan_solve(lab_sim, 1, 2, 2, PlanConfig(check_collisions=False))


def test_csv_round_trips_every_sample(plan: Plan) -> None:
    tr = plan.trajectory
    rows = list(csv.reader(io.StringIO(trajectory_csv(tr))))
    assert rows[0] == ["t", *(f"q{i}" for i in range(1, 7)), *(f"qd{i}" for i in range(1, 7)), "suction"]
    data = np.array(rows[1:], dtype=float)
    assert data.shape == (len(tr.t), 14)
    np.testing.assert_allclose(data[:, 0], tr.t, rtol=0, atol=5e-7)  # t is printed with 6 decimals
    np.testing.assert_array_equal(data[:, 1:7], tr.q)  # repr round-trips float64 exactly
    np.testing.assert_array_equal(data[:, 7:13], tr.qd)
    np.testing.assert_array_equal(data[:, 13], tr.suction.astype(float))


def test_json_summary(plan: Plan) -> None:
    d = json.loads(json.dumps(plan.to_json_dict()))
    assert (d["start_tower"], d["end_tower"], d["blocks"]) == (2, 3, 2)
    assert d["moves"][0] == {"block": 2, "from_tower": 2, "from_height": 2, "to_tower": 1, "to_height": 1}
    assert d["samples"] == len(plan.trajectory.t) and d["rate_hz"] == 125.0
    assert d["duration_s"] == plan.duration_s
    assert d["motion_s"] == pytest.approx(plan.duration_s - 6 * 0.3)  # 3 moves, 2 dwells of 0.3 s each
    assert plan.limits is not None
    np.testing.assert_array_equal(d["velocity_limit"], plan.limits.v_max)
    assert np.all(np.array(d["max_abs_velocity"]) <= plan.limits.v_max * (1 + 1e-6))
    assert d["violations"] == [] and set(d["planning_time_s"]) >= {"build", "ruckig", "sampling", "checks"}
