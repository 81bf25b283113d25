"""The planner's results in the user's cache (ur3hanoi.plan.route.stored, ur3hanoi.plan.motion.waypoints): a plan from
the cache equals a fresh one bit for bit without running the optimiser, corrupt or foreign entries are rebuilt, a
changed setting is a new entry, and two processes racing on an empty cache are safe."""

from __future__ import annotations

import base64
import hashlib
import json
import subprocess
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import ur3hanoi.plan.motion.waypoints as waypoints
import ur3hanoi.plan.route.connections as connections
from tests.support.cache_race import start_racer
from ur3hanoi.plan import Plan, PlanConfig, plan_solve
from ur3hanoi.plan.motion.waypoints import WAYPOINTS
from ur3hanoi.plan.route.stored import CONNECTION
from ur3hanoi.station.calibration import Station


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    _forget()
    yield tmp_path / "xdg" / "ur3hanoi"
    _forget()


def _forget() -> None:
    """What a new process starts with: no planner or waypoints in memory (the user's cache is kept)."""
    connections._cached_planner.cache_clear()
    waypoints._cached_waypoints.cache_clear()


def _no_optimiser(monkeypatch: pytest.MonkeyPatch) -> None:
    import scipy.optimize

    def refuse(*args: object, **kwargs: object) -> None:
        raise AssertionError("the optimiser ran although the cache holds the plan's connections")

    monkeypatch.setattr(scipy.optimize, "minimize", refuse)


def _assert_same_plan(a: Plan, b: Plan) -> None:
    """Bit for bit: every sample, every segment boundary and the durations."""
    for name in ("t", "q", "qd", "qdd", "qddd", "suction", "move_index", "phase"):
        np.testing.assert_array_equal(getattr(b.trajectory, name), getattr(a.trajectory, name), err_msg=name)
    assert [(s.phase, s.t_start, s.duration) for s in b.segments] == [(s.phase, s.t_start, s.duration)
                                                                       for s in a.segments]
    for sa, sb in zip(a.segments, b.segments, strict=True):
        np.testing.assert_array_equal(sb.q_end, sa.q_end)
    assert (b.duration_s, b.stop_and_go_duration_s, b.vertical_deviation_m) == (
        a.duration_s, a.stop_and_go_duration_s, a.vertical_deviation_m)
    assert b.violations == a.violations


def _entries(cache: Path, kind: str) -> list[Path]:
    return sorted(cache.glob(f"{kind}-*.cache"))


def test_plan_from_the_cache_equals_a_fresh_one(lab_sim: Station, private_cache: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    fresh = plan_solve(lab_sim, 0, 2, 3)
    assert len(_entries(private_cache, CONNECTION)) == 13 and len(_entries(private_cache, WAYPOINTS)) == 1
    _forget()
    _no_optimiser(monkeypatch)
    _assert_same_plan(fresh, plan_solve(lab_sim, 0, 2, 3))


def test_another_setting_is_another_entry(lab_sim: Station, private_cache: Path) -> None:
    plan_solve(lab_sim, 0, 2, 2)
    n = len(_entries(private_cache, CONNECTION))
    _forget()
    slow = plan_solve(lab_sim, 0, 2, 2, PlanConfig(speed=0.5))
    assert len(_entries(private_cache, CONNECTION)) == 2 * n  # nothing shared with speed 1
    _forget()
    _assert_same_plan(slow, plan_solve(lab_sim, 0, 2, 2, PlanConfig(speed=0.5)))


def _rewrite(entry: Path, payload: bytes) -> None:
    """A whole entry (header digest and length matching) holding ``payload``."""
    head = json.loads(entry.read_bytes().split(b"\n", 1)[0])
    head.update(length=len(payload), sha256=hashlib.sha256(payload).hexdigest())
    entry.write_bytes(json.dumps(head).encode() + b"\n" + base64.b64encode(payload) + b"\n")


@pytest.mark.parametrize("how", ["payload byte changed", "truncated", "entry of another key",
                                 "whole entry, payload not a plan"])
def test_corrupt_or_foreign_entries_are_rebuilt(lab_sim: Station, private_cache: Path, how: str) -> None:
    fresh = plan_solve(lab_sim, 0, 2, 2)
    entries = [*_entries(private_cache, CONNECTION), *_entries(private_cache, WAYPOINTS)]
    originals = {e: e.read_bytes() for e in entries}
    for i, e in enumerate(entries):
        raw = e.read_bytes()
        if how == "payload byte changed":  # the digest no longer matches: never decoded
            head, body = raw.split(b"\n", 1)
            e.write_bytes(head + b"\n" + (b"B" if body[:1] == b"A" else b"A") + body[1:])
        elif how == "truncated":
            e.write_bytes(raw[: len(raw) // 2])
        elif how == "entry of another key":  # another connection's whole entry under this name
            e.write_bytes(originals[entries[(i + 1) % len(entries)]])
        elif how == "whole entry, payload not a plan":  # digest and length match: the decoder refuses it
            _rewrite(e, json.dumps({"exit": [1, 2], "across": "x"}).encode() if i % 2 else b"\x93NUMPY junk")
    _forget()
    _assert_same_plan(fresh, plan_solve(lab_sim, 0, 2, 2))
    assert {e: e.read_bytes() for e in entries} == originals  # rebuilt, whole again


_RACE_BODY = """
    from ur3hanoi.plan import plan_solve
    plan = plan_solve(station, 0, 2, 2)
    tr = plan.trajectory
    digest = hashlib.sha256(b"".join(x.tobytes() for x in (tr.t, tr.q, tr.qd, tr.qdd, tr.qddd))).hexdigest()
    misses = [kind for event, kind in cache_events if event == "miss" and kind.startswith("plan-")]
    print(len(misses), digest, "scipy" if "scipy" in sys.modules else "-")
"""


def _racer(ready: Path, hold_s: float, n_racers: int) -> subprocess.Popen[str]:
    return start_racer(_RACE_BODY, ready, hold_s, n_racers)


def test_two_processes_racing_on_an_empty_cache(private_cache: Path, tmp_path: Path) -> None:
    """Both miss and build at once and both write; both plan the same, only whole entries remain; a third process
    then plans from the cache alone (no miss, SciPy never imported) and gets the same plan."""
    procs = [_racer(tmp_path / "ready", 0.2, 2) for _ in range(2)]
    outs = [p.communicate(timeout=300) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    (miss_a, digest_a, _), (miss_b, digest_b, _) = (out.split() for out, _ in outs)
    assert int(miss_a) > 0 and int(miss_b) > 0 and digest_a == digest_b
    entries = sorted(private_cache.iterdir())
    assert {p.suffix for p in entries} == {".cache"}, entries
    third = _racer(tmp_path / "ready-third", 0.0, 1)
    out, err = third.communicate(timeout=300)
    assert third.returncode == 0, err
    assert out.split() == ["0", digest_a, "-"]
    assert sorted(private_cache.iterdir()) == entries
