"""Which pose teach names next: a contact on every tower first (the stack's top block on its tower), then the slot
that makes the most points checkable by the audit's rule."""

from __future__ import annotations

import pytest

from tests.conftest import LAB_REAL, LAB_SIM
from ur3hanoi.calibrate.grid_fit import choose_model, removable
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.teach.advice import next_pose, required_height


@pytest.fixture(scope="module")
def base() -> Station:
    return load_station(LAB_REAL)


def test_every_tower_first_the_stack_on_its_top_block(base: Station) -> None:
    a = next_pose(base, [], start=0)
    assert a is not None and (a.tower, a.height, a.required) == (0, 2, True)
    assert "tower(s) 1, 2 and 3 have none yet (the top block of the stack)" in a.why
    a = next_pose(base, [(0, 2, 0)], start=0)
    assert a is not None and (a.tower, a.height) == (1, 0) and "(a block on the table)" in a.why
    a = next_pose(base, [], start=1)
    assert a is not None and (a.tower, a.height) == (0, 0)
    assert [required_height(base, t, 1) for t in range(3)] == [0, 2, 0]


def test_a_flat_station_is_taught_on_its_first_row() -> None:
    flat = load_station(LAB_SIM)
    assert [required_height(flat, t, 0) for t in range(flat.n_towers)] == [0] * flat.n_towers


def test_skipped_poses_are_not_named_again(base: Station) -> None:
    a = next_pose(base, [(0, 2, 0)], start=0, skipped={(1, 0)})
    assert a is not None and (a.tower, a.height) == (2, 0)
    assert next_pose(base, [(0, 2, 0)], start=0, skipped={(1, 0), (2, 0)}) is None


def test_then_the_slot_that_makes_the_most_points_checkable(base: Station) -> None:
    taught = [(0, 2, 0), (1, 0, 0), (2, 0, 0), (0, 0, 0)]
    a = next_pose(base, taught, start=0)
    assert a is not None and not a.required
    model = choose_model(base, taught)
    assert model is not None and int(removable(model, taught).sum()) == 0  # all unchecked before
    after = [*taught, (a.tower, a.height, 0)]
    model = choose_model(base, after)
    assert model is not None and int(removable(model, after).sum()) == 4  # tower 3 alone stays unchecked
    assert a.why.startswith("tower 2 rests on one pose: nothing checks where it stands along the table (a joint-1 "
                            "offset would move it unseen); a second height checks it (then tower(s) 3). f writes "
                            "without it, with that note")
    for t in range(3):  # no other slot makes more checkable
        for h in range(3):
            if (t, h, 0) not in after:
                other = [*taught, (t, h, 0)]
                m = choose_model(base, other)
                assert m is None or int(removable(m, other).sum()) <= 4


def test_with_every_point_checked_more_is_optional(base: Station) -> None:
    taught = [(t, h, 0) for t in range(3) for h in (0, 2)]
    a = next_pose(base, taught, start=0)
    assert a is not None and a.why.startswith("optional: every point is checked by the others")
    every = [(t, h, 0) for t in range(3) for h in range(3)]
    assert next_pose(base, every, start=0) is None


def test_the_guidance_leads_to_every_tower_checked_by_a_second_pose(base: Station) -> None:
    """Issue 37: a tower resting on one pose may stand anywhere along the table; teach names a second height of
    each such tower before anything else, so following it gives a set where every tower is checked."""
    taught: list[tuple[int, int, int]] = []
    named = []
    while True:
        a = next_pose(base, taught, start=0)
        if a is None or all(sum(1 for t, _, _ in taught if t == u) >= 2 for u in range(3)):
            break
        named.append((a.tower, a.height))
        taught.append((a.tower, a.height, 0))
    assert named[:3] == [(0, 2), (1, 0), (2, 0)] and len(named) == 6  # the required three, then one more each
    assert sorted(t for t, _ in named[3:]) == [0, 1, 2]
