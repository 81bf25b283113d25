"""Clearance checks (plan.checks.collision): clean plans pass, crafted collisions and clearances are reported."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from ur3hanoi.errors import PlanError
from ur3hanoi.plan import Phase, Plan, PlanConfig, build_waypoints, check_collisions, plan_solve
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON


@pytest.fixture(scope="module")
def plan(lab_sim: Station) -> Plan:
    return plan_solve(lab_sim, 0, 2, 2, PlanConfig(check_collisions=False))


def _check(plan: Plan, q: np.ndarray | None = None, **config: float) -> list[str]:
    assert plan.limits is not None
    tr = plan.trajectory if q is None else dataclasses.replace(plan.trajectory, q=q)
    return check_collisions(tr, plan.moves, plan.station, plan.n_blocks, plan.start,
                            dataclasses.replace(plan.config, **config), plan.limits)


def test_clean_plans_have_clearance(shipped_station: Station) -> None:
    """Also guards the exclusions (contact by design): the cup touches each moved block, and each carried block
    rests on the table (flat lab_sim) or on the block under it (stacked lab_real)."""
    plan = plan_solve(shipped_station, 0, 2, 2, PlanConfig(check_collisions=False))
    assert _check(plan) == []


def test_cup_inside_a_resting_block_is_reported(plan: Plan) -> None:
    """The first transit parked at the contact pose of a resting block: the cup is inside it."""
    tr = plan.trajectory
    transit = np.flatnonzero((tr.phase == int(Phase.TRANSIT)) & (tr.move_index == 0))
    q = tr.q.copy()
    q[transit] = build_waypoints(plan.station).table[plan.start, 0, ON]
    viol = _check(plan, q)
    assert len(viol) == 5  # the first five are reported
    assert all(v.startswith("cup is -") and "(TRANSIT, move 1)" in v for v in viol)


def test_carried_block_clearance_is_reported(lab_real: Station) -> None:
    """An impossible 20 cm block clearance must be reported (the check is live)."""
    cfg = PlanConfig(clearance_m=0.2, raise_on_violation=False)
    plan = plan_solve(lab_real, 0, 2, 2, cfg)
    assert any(v.startswith("carried_block is") and "required 200.0 mm" in v for v in plan.violations)
    with pytest.raises(PlanError, match="carried_block"):
        plan_solve(lab_real, 0, 2, 2, dataclasses.replace(cfg, raise_on_violation=True))
