"""Waypoint generation: every pose of the table by IK on the home branch, and the FK check that flags bad entries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ur3hanoi.errors import TableError
from ur3hanoi.robot.ik_solvers import pose_errors
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import T_world_tcp, pose_label
from ur3hanoi.tables.ik_table import check_table, generate_table


def test_every_pose_reaches_its_target(shipped_station: Station) -> None:
    table = generate_table(shipped_station)
    assert table.q.shape == (shipped_station.n_towers, shipped_station.n_heights, 2, 6)
    robot = load_ur3(shipped_station.tool, shipped_station.limits)
    for t in range(shipped_station.n_towers):
        for h in range(shipped_station.n_heights):
            for k in (0, 1):
                T = shipped_station.T_world_base * robot.fk(table.q[t, h, k])
                dp, dr = pose_errors(T, T_world_tcp(shipped_station, t, h, k))
                assert dp <= 1e-9 and dr <= 1e-9, pose_label(t, h, k)
    assert table.max_position_error <= 1e-9 and table.max_orientation_error <= 1e-9


def test_check_table_passes_a_generated_table(shipped_station: Station) -> None:
    rows = check_table(generate_table(shipped_station).q, shipped_station)
    assert len(rows) == shipped_station.n_towers * shipped_station.n_heights * 2
    assert all(r.ok for r in rows)
    assert max(r.position_error_mm for r in rows) <= 1e-6  # 1e-9 m
    assert max(r.orientation_error_deg for r in rows) <= math.degrees(1e-9)


def test_check_table_flags_a_bad_entry(lab_real: Station) -> None:
    q = generate_table(lab_real).q.copy()
    q[1, 2, 0, 1] += 0.01  # 10 mrad on the shoulder: several mm at the tool
    rows = check_table(q, lab_real)
    bad = [r for r in rows if not r.ok]
    assert [(r.tower, r.height, r.k) for r in bad] == [(1, 2, 0)]
    assert bad[0].position_error_mm > 1.0


def test_check_table_tolerance_is_applied(lab_real: Station) -> None:
    q = generate_table(lab_real).q.copy()
    q[0, 0, 1, 0] += 0.002  # 2 mrad on the pan: about 0.6 mm at the tool
    assert all(r.ok for r in check_table(q, lab_real, tol_mm=1.0))
    assert sum(not r.ok for r in check_table(q, lab_real, tol_mm=0.1)) == 1


def test_check_table_shape_mismatch(lab_real: Station) -> None:
    with pytest.raises(TableError, match="2 towers x 3 heights"):
        check_table(np.zeros((2, 3, 2, 6)), lab_real)


def test_pose_label_numbers_from_1() -> None:
    assert pose_label(0, 0, 0) == "tower 1 height 1 on"
    assert pose_label(2, 1, 1) == "tower 3 height 2 above"


def test_check_table_skips_missing_entries(lab_real: Station) -> None:
    q = generate_table(lab_real).q.copy()
    q[1, 2, 1] = np.nan
    rows = check_table(q, lab_real)
    assert len(rows) == 17 and all(r.ok for r in rows)
    assert (1, 2, 1) not in {(r.tower, r.height, r.k) for r in rows}
