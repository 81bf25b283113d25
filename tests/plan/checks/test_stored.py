"""Clearance results in the user's cache (ur3hanoi.plan.checks.stored): a plan read from the cache is not re-checked
and gets the violations the check gives, a changed station, setting or motion is checked afresh, a corrupt entry is
rebuilt."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import ur3hanoi.plan.checks.clearance as clearance
import ur3hanoi.plan.motion.waypoints as waypoints
import ur3hanoi.plan.route.connections as connections
from ur3hanoi.io.cache import installed_versions
from ur3hanoi.plan import Plan, plan_solve
from ur3hanoi.plan.checks.stored import CLEARANCE, check_segments
from ur3hanoi.station.calibration import Station


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    connections._cached_planner.cache_clear()
    waypoints._cached_waypoints.cache_clear()
    yield tmp_path / "xdg" / "ur3hanoi"
    connections._cached_planner.cache_clear()
    waypoints._cached_waypoints.cache_clear()


@pytest.fixture
def plan(lab_sim: Station) -> Plan:
    return plan_solve(lab_sim, 0, 2, 2)


@pytest.fixture
def checks(monkeypatch: pytest.MonkeyPatch) -> list[int]:
    """Counts the runs of the real clearance check (each one delegates to it)."""
    runs: list[int] = []
    real = clearance.check_segments

    def counted(*args: object, **kwargs: object) -> list[str]:
        runs.append(1)
        return real(*args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(clearance, "check_segments", counted)
    return runs


def _check(plan: Plan, station: Station | None = None, trajectory: object = None, **config: float) -> list[str]:
    return check_segments(plan.segments, plan.moves, station or plan.station, plan.n_blocks, plan.start,
                          dataclasses.replace(plan.config, **config), plan.limits,
                          trajectory or plan.trajectory)  # type: ignore[arg-type]


def test_a_plan_from_the_cache_is_not_checked_again(plan: Plan, private_cache: Path, checks: list[int]) -> None:
    assert len(sorted(private_cache.glob(f"{CLEARANCE}-*.cache"))) == 1  # the plan's own check, kept
    assert _check(plan) == list(plan.violations) == []
    assert checks == []  # read back, not re-checked


def test_violations_read_back_as_the_check_gave_them(plan: Plan, checks: list[int]) -> None:
    """A 10 cm clearance between blocks cannot hold next to a stack: the check's messages are kept and read back."""
    direct = clearance.check_segments(plan.segments, plan.moves, plan.station, plan.n_blocks, plan.start,
                                      dataclasses.replace(plan.config, clearance_m=0.1), plan.limits)
    assert direct and all("required 100.0 mm" in v for v in direct)
    assert _check(plan, clearance_m=0.1) == direct
    assert _check(plan, clearance_m=0.1) == direct
    assert len(checks) == 2  # the direct call and the first cached one


def test_a_changed_station_or_motion_is_checked_afresh(plan: Plan, checks: list[int]) -> None:
    moved = dataclasses.replace(plan.station, block_size=plan.station.block_size + 1e-4)
    _check(plan, station=moved)
    assert len(checks) == 1
    renamed = dataclasses.replace(plan.station, name="elsewhere", source="elsewhere.yaml")
    _check(plan, station=renamed)  # name and file are not geometry: the same entry
    assert len(checks) == 1
    tr = plan.trajectory
    nudged = dataclasses.replace(tr, q=np.where(np.arange(len(tr.q))[:, None] == 7, np.nextafter(tr.q, 9.0), tr.q))
    _check(plan, trajectory=nudged)  # one sample moved by one ulp
    assert len(checks) == 2
    _check(plan, collision_rate_hz=plan.config.collision_rate_hz * 2)
    assert len(checks) == 3


@pytest.mark.parametrize("how", ["payload byte changed", "truncated", "not a list of messages"])
def test_a_corrupt_entry_is_rebuilt(plan: Plan, private_cache: Path, checks: list[int], how: str) -> None:
    (entry,) = sorted(private_cache.glob(f"{CLEARANCE}-*.cache"))
    original = entry.read_bytes()
    head, body = original.split(b"\n", 1)
    if how == "payload byte changed":
        entry.write_bytes(head + b"\n" + (b"B" if body[:1] == b"A" else b"A") + body[1:])
    elif how == "truncated":
        entry.write_bytes(original[: len(original) // 2])
    else:  # digest and length match, the decoder refuses it
        import ur3hanoi.io.cache as cache

        header = json.loads(head)
        payload = json.dumps({"violations": 1}).encode()
        entry.unlink()
        assert cache.store(CLEARANCE, header["key"], payload)
    assert _check(plan) == list(plan.violations)
    assert checks == [1]
    assert entry.read_bytes() == original  # rebuilt, whole again


def test_library_versions_are_read_without_importing_them() -> None:
    import importlib.metadata

    versions = dict(installed_versions(("pin", "coal", "example_robot_data", "no-such-distribution")))
    assert versions == {"pin": importlib.metadata.version("pin"), "coal": importlib.metadata.version("coal"),
                        "example_robot_data": importlib.metadata.version("example-robot-data"),
                        "no-such-distribution": None}
