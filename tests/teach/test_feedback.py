"""After each record from the third point on: every point's residual and the suspects, so a pose 15 mm off is named
at once, whether the points alone can check it (the calibration's fit) or only the base's layout can."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.conftest import LAB_REAL
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.tables.ik_table import generate_table
from ur3hanoi.teach.feedback import BY_LAYOUT, BY_POINTS, feedback
from ur3hanoi.teach.jog import Jogger


@pytest.fixture(scope="module")
def base() -> Station:
    return load_station(LAB_REAL)


@pytest.fixture(scope="module")
def hidden(base: Station) -> Station:
    """The station as it really stands: the base's towers turned 2 deg about their centroid, moved 5, -4, 1 mm."""
    o = np.asarray(base.tower_origins)
    c, s = math.cos(math.radians(2.0)), math.sin(math.radians(2.0))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    moved = (o - o.mean(axis=0)) @ R.T + o.mean(axis=0) + np.array([0.005, -0.004, 0.001])
    return base.with_grid(moved, base.height_step, base.tool_yaw)


def taught(hidden: Station, slots: list[tuple[int, int]], off_mm: dict[int, tuple[float, float, float]]
           ) -> TaughtPoints:
    """Contact poses of ``hidden`` at ``slots`` (0-based), point i moved by ``off_mm[i]`` (by IK)."""
    q = generate_table(hidden).q
    jog = Jogger(hidden)
    points = []
    for i, (t, h) in enumerate(slots):
        qi = q[t, h, 0]
        if i in off_mm:
            target = jog.step(qi, off_mm[i])
            assert target.q is not None
            qi = target.q
        points.append(TaughtPoint(index=i, tower=t, height=h, k=0, q=tuple(float(v) for v in qi)))
    return TaughtPoints(points=tuple(points), source="<test>", sha256="")


FIRST = [(0, 2), (1, 0), (2, 0)]
ALL_CHECKED = [*FIRST, (0, 0), (1, 2), (2, 2)]


def test_three_good_points_agree_judged_by_the_layout(base: Station, hidden: Station) -> None:
    fb = feedback(base, taught(hidden, FIRST, {0: (0.7, -0.5, 0.4), 2: (0.0, 0.8, -0.3)}), "lab_real")
    assert fb.suspects == () and fb.problem == "" and fb.fit is not None
    assert all(r.by == BY_LAYOUT and r.off_mm < 3.0 and not r.suspect for r in fb.rows)
    assert math.isclose(fb.layout_turn_deg, 2.0, abs_tol=0.5)
    text = "\n".join(fb.lines("lab_real"))
    assert "every point agrees with the others" in text and "the layout of lab_real" in text


def test_a_third_pose_15_mm_off_is_named_at_once(base: Station, hidden: Station) -> None:
    fb = feedback(base, taught(hidden, FIRST, {2: (0.0, 0.0, 15.0)}), "lab_real")
    assert [i for i, _ in fb.suspects] == [2]
    row = fb.rows[2]
    assert row.suspect and math.isclose(row.off_mm, 15.0, abs_tol=1.5)
    assert fb.suspects[0][1].startswith(f"tower 3 height 1 is {row.off_mm:.1f} mm from where the other points put "
                                        "it (with the tower spacing and block size of lab_real): re-record it?")
    assert not fb.rows[0].suspect and fb.rows[0].off_mm < 2.0


def test_points_the_others_check_are_judged_by_the_calibrations_fit(base: Station, hidden: Station) -> None:
    fb = feedback(base, taught(hidden, ALL_CHECKED, {4: (15.0, 0.0, 0.0)}), "lab_real")
    assert all(r.by == BY_POINTS for r in fb.rows)
    assert [i for i, _ in fb.suspects] == [4]
    assert fb.suspects[0][1].startswith("tower 2 height 3 is suspect: ") and "re-record it?" in fb.suspects[0][1]
    assert fb.fit is not None and fb.fit.suspects[0].index == 4


def test_too_few_towers_says_why_there_is_no_calibration_yet(base: Station, hidden: Station) -> None:
    fb = feedback(base, taught(hidden, [(0, 2), (1, 0), (1, 1)], {}), "lab_real")
    assert fb.fit is None and "tower(s) 3 have none" in fb.problem
    assert "no calibration yet: " in "\n".join(fb.lines("lab_real"))
