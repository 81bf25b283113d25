"""Which taught point is wrong, on all the evidence (issue 33): the injection matrix over the shipped stations and
hidden ones (tests/support/gross_matrix.py: every outcome named-and-left-out, refused naming the point, or an error
the evidence cannot see kept within the always-flagged limit), and the decision itself: 1 mm of hand error is
never named, a pose 15 mm off is named, two points nothing tells apart are both named, a point vouched for is never
left out."""

from __future__ import annotations

from collections import Counter

import numpy as np
import pytest

from tests.support import gross_matrix as gm
from tests.support import recorded_tables as rt
from ur3hanoi.calibrate.consensus import AMBIGUOUS_SCORE, consensus
from ur3hanoi.calibrate.grid_fit import measure
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import contact_point_world
from ur3hanoi.tables.ik_table import generate_table
from ur3hanoi.teach.jog import Jogger

TRUTHS = {t.name: t for t in gm.truths()}
FIRST = [(0, 2, 0), (1, 0, 0), (2, 0, 0)]  # what teach names first: the top of the stack, then the table


def check_cases(cases: list[gm.Case]) -> Counter[str]:
    counts: Counter[str] = Counter()
    failures = []
    for case in cases:
        kind, said = gm.outcome(case)
        counts[kind] += 1
        if kind not in gm.ALLOWED or (kind == "refused" and case.label.split(" [")[0] not in said):
            failures.append(f"{case}: {kind}: {said}")  # refused: the error line names the wrong point too
    assert failures == [], "\n".join(failures)
    return counts


@pytest.mark.parametrize("name", sorted(TRUTHS))
def test_one_gross_error_is_named_and_left_out_or_nothing_is_written(name: str) -> None:
    """The fast share of the matrix: the minimal file with every error in every slot, a 6-point file with one
    error per slot."""
    counts = check_cases(list(gm.fast_cases(TRUTHS[name])))
    # In the minimal file every wrong point is its tower's only contact: named and nothing written, or too small
    # to see (a joint off by 2 deg moves the cup a few mm), or moving its tower along the table only (a joint-1
    # offset; on the flat lab_sim a slot one height off): written, and said (issue 37).
    assert counts["refused"] + counts["undecided"] + counts["said"] >= 12 and counts["named"] >= 1, counts
    assert counts["said"] <= 8, counts  # never most of them


@pytest.mark.slow
@pytest.mark.parametrize("name", sorted(TRUTHS))
def test_the_whole_matrix(name: str) -> None:
    """Every file (3 to 9 points), every slot, every error."""
    counts = check_cases(list(gm.cases(TRUTHS[name])))
    # Issue 37: an error that moves a tower taught once along the table only is written and said (on the flat
    # lab_sim a slot one height off is such a move too): never more than a tenth of the cases.
    total = sum(counts.values())
    assert counts["named"] + counts["refused"] + counts["undecided"] + counts["said"] >= 0.9 * total, counts
    assert counts["said"] <= 0.11 * total, counts


def test_the_matrix_is_the_issue_s_cases() -> None:
    t = TRUTHS["lab_real"]
    files = gm.files(t)
    assert [len(s) for s in files.values()] == [3, 5, 4, 6, 7, 9]
    assert files["example"] == [(0, 0, 0), (1, 0, 0), (2, 0, 0), (0, 2, 0), (2, 1, 1)]  # the shipped example's slots
    home = next(c for c in gm.cases(t, {"example": files["example"]}, kinds=("home",)) if c.wrong == 1)
    assert np.array_equal(home.taught.points[1].q, t.base.q_home)
    assert gm.outcome(home)[0] == "refused"  # tower 2's only contact: nothing written
    assert "the arm was at home" in gm.outcome(home)[1]


@pytest.fixture(scope="module")
def hidden() -> Station:
    return gm.hidden(load_station("lab_real"), 2.0, (5.0, -4.0, 1.0), 0)


def taught(hidden: Station, slots: list[tuple[int, int, int]], off_mm: dict[int, np.ndarray]) -> list[np.ndarray]:
    """Contact poses of ``hidden`` at ``slots``, point i moved by ``off_mm[i]`` (by IK)."""
    q, jog = generate_table(hidden).q, Jogger(hidden)
    out = []
    for i, s in enumerate(slots):
        target = jog.step(q[s], tuple(float(v) for v in off_mm.get(i, np.zeros(3))))
        assert target.q is not None
        out.append(target.q)
    return out


def unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def test_hand_errors_of_1_mm_are_never_named(hidden: Station) -> None:
    base, rng = load_station("lab_real"), np.random.default_rng(7)
    for _ in range(30):
        qs = taught(hidden, FIRST, {i: unit(rng) for i in range(3)})
        assert consensus(base, FIRST, measure(base, qs), np.ones(3, dtype=bool)).kind == "agree"


@pytest.mark.parametrize("bad", [0, 1, 2])
def test_a_pose_15_mm_off_the_table_s_level_is_named_whichever_it_is(hidden: Station, bad: int) -> None:
    base, rng = load_station("lab_real"), np.random.default_rng(bad)
    first = 0
    for _ in range(20):
        off = {i: 0.6 * unit(rng) for i in range(3)}
        off[bad] = off[bad] + np.array([*(5.0 * unit(rng)[:2]), float(rng.choice([-15.0, 15.0]))])
        c = consensus(base, FIRST, measure(base, taught(hidden, FIRST, off)), np.ones(3, dtype=bool))
        assert c.kind in ("named", "undecided") and bad in c.wrong and c.alone  # each is its tower's only contact
        first += c.wrong[0] == bad
    assert first == 20  # named first every time (alone, or with a rival the points cannot rule out)


@pytest.mark.parametrize("bad", [0, 1, 2])
def test_a_tower_taught_once_may_stand_anywhere_on_the_table(hidden: Station, bad: int) -> None:
    """Issue 37: nothing but the base's layout could say a tower taught once stands 15-110 mm along the table from
    where that layout puts it, and real towers do: the points agree."""
    base, rng = load_station("lab_real"), np.random.default_rng(10 + bad)
    for mm in (15.0, 50.0, 110.0):
        a = float(rng.uniform(-np.pi, np.pi))
        qs = [rt.pose_q(hidden, contact_point_world(hidden, t, h) + (mm * 1e-3 * np.array([np.cos(a), np.sin(a), 0.0])
                                                                    if i == bad else 0.0), rt.R_tcp(hidden.tool_yaw))
              for i, (t, h, _) in enumerate(FIRST)]
        c = consensus(base, FIRST, measure(base, qs), np.ones(3, dtype=bool))
        assert c.kind == "agree", (mm, c.kind, [ch for ch in c.whole.checks if ch.over])
        # Judged by the table's level alone (the hidden towers stand up to 1.5 mm from their layout).
        assert c.whole.by[bad] == "level" and c.whole.off_mm[bad] == pytest.approx(0.0, abs=2.0)


def test_two_points_nothing_tells_apart_are_both_named(hidden: Station) -> None:
    slots = [*FIRST, (0, 0, 0), (1, 2, 0), (2, 2, 0)]
    base = load_station("lab_real")
    qs = taught(hidden, slots, {1: np.array([5.0, 0.0, 0.0]), 4: np.array([-6.0, 0.0, 0.0])})
    c = consensus(base, slots, measure(base, qs), np.ones(6, dtype=bool))
    assert c.kind == "undecided" and sorted(c.wrong) == [1, 4]
    assert abs(c.tried[1].score - c.tried[4].score) < AMBIGUOUS_SCORE
    # Sideways, nothing but the layout could tell them apart, however far: still both named.
    qs = taught(hidden, slots, {1: np.array([5.0, 0.0, 0.0]), 4: np.array([-16.0, 0.0, 0.0])})
    c = consensus(base, slots, measure(base, qs), np.ones(6, dtype=bool))
    assert c.kind == "undecided" and sorted(c.wrong) == [1, 4]
    # The table's level decides once one of them is off in height: left alone, it would stand 16 mm low.
    qs = taught(hidden, slots, {1: np.array([5.0, 0.0, 0.0]), 4: np.array([0.0, 0.0, -16.0])})
    c = consensus(base, slots, measure(base, qs), np.ones(6, dtype=bool))
    assert c.kind == "named" and c.wrong == (4,) and not c.alone


def test_a_point_vouched_for_is_never_left_out_and_its_tower_not_judged(hidden: Station) -> None:
    base = load_station("lab_real")
    qs = taught(hidden, FIRST, {1: np.array([0.0, 0.0, 30.0])})  # tower 2 really stands on a 30 mm plinth
    m = measure(base, qs)
    said = consensus(base, FIRST, m, np.ones(3, dtype=bool))
    assert said.kind == "named" and said.wrong == (1,) and said.alone
    vouched = consensus(base, FIRST, m, np.ones(3, dtype=bool), accepted=np.array([False, True, False]))
    assert vouched.kind == "agree"
    assert not any(c.what in ("level", "lean") and c.index == 1 for c in vouched.whole.checks)


def test_a_tower_tilted_alike_is_the_tower_s_a_single_tilted_point_is_wrong(hidden: Station) -> None:
    """Issue 37: every contact of one tower tilted 6.5 deg is how the student held the wrist there; one contact
    tilted 6.5 deg among its tower's others is wrong."""
    base, q = load_station("lab_real"), generate_table(hidden).q
    slots = [(t, h, 0) for t in range(3) for h in range(3)]
    qs = []
    for t, h, k in slots:
        p = contact_point_world(hidden, t, h)
        qs.append(rt.pose_q(hidden, p, rt.R_tcp(hidden.tool_yaw, 6.5, 0.7)) if t == 2 else q[t, h, k])
    c = consensus(base, slots, measure(base, qs), np.ones(9, dtype=bool))
    assert c.kind == "agree", [ch for ch in c.whole.checks if ch.over]
    one = list(qs)
    for i in (6, 8):
        one[i] = q[slots[i]]  # tower 3: only its height 2 tilted
    c = consensus(base, slots, measure(base, one), np.ones(9, dtype=bool))
    assert c.kind == "named" and c.wrong == (7,)
    tilt = [ch for ch in c.whole.checks if ch.what == "tilt" and ch.index == 7]
    assert tilt and tilt[0].value == pytest.approx(6.5, abs=0.01)  # from the mean of its two mates' axes


def test_a_tower_alone_fixing_the_step_is_checked_by_the_block_size() -> None:
    """Tower 1 taught at heights 1 and 3 (the others once): its height 1 recorded with height 2's pose halves the
    step. Nothing but the base's block size says so, and the pose that leaves tower 1 on the table is the one."""
    base = load_station("lab_real")
    q = generate_table(base).q
    slots = [(0, 2, 0), (1, 0, 0), (2, 0, 0), (0, 0, 0)]
    qs = [q[s] for s in slots]
    qs[3] = q[0, 1, 0]
    c = consensus(base, slots, measure(base, qs), np.ones(4, dtype=bool))
    assert not any(ch.what == "point" for ch in c.whole.checks)  # the points cannot check each other
    step = [ch for ch in c.whole.checks if ch.what == "step"]
    assert len(step) == 1 and step[0].over and step[0].value == pytest.approx(2 * 15.9, abs=0.1)
    assert c.kind == "named" and c.wrong == (3,) and not c.alone
