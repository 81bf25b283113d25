"""Explaining a deviation: the joint a typo is in (via FK), swapped, copied and misplaced entries."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tests.support import recorded_tables as rt
from ur3hanoi.calibrate.explain import (
    JOINT_LABELS,
    angle_text,
    duplicates,
    find_swaps,
    joint_typo,
    nearest_slot,
    swap_kind,
)
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, ON, T_world_tcp


@pytest.mark.parametrize("delta_deg", [10.0, -3.0])
@pytest.mark.parametrize("joint", range(6))
@pytest.mark.parametrize("station", ["lab_real", "lab_sim"])
def test_joint_typo_finds_the_joint_and_its_value(station: str, joint: int, delta_deg: float) -> None:
    st = load_station(station)
    rng = np.random.default_rng(joint)
    q = rt.recorded_q(st, rng)  # 1-3 mm, 0-0.5 deg of noise on every pose
    slot = (int(rng.integers(3)), int(rng.integers(3)), int(rng.integers(2)))
    typo_q = rt.typo(q, slot, joint, delta_deg)[slot]
    found = joint_typo(load_ur3(st.tool, st.limits), st.T_world_base, typo_q, T_world_tcp(st, *slot).translation,
                       st.tool_yaw, tol_mm=6.0, tol_deg=2.0)
    assert found is not None and found.joint == joint and found.explains
    assert found.recorded == typo_q[joint]
    assert math.degrees(found.predicted - q[slot][joint]) == pytest.approx(0.0, abs=0.6)
    assert found.describe().startswith(f"a typo in joint {joint + 1} ({JOINT_LABELS[joint]}): recorded ")


def test_no_typo_in_an_exact_pose(lab_real: Station) -> None:
    q = rt.recorded_q(lab_real, None)[0, 0, ON]
    found = joint_typo(load_ur3(lab_real.tool, lab_real.limits), lab_real.T_world_base, q,
                       T_world_tcp(lab_real, 0, 0, ON).translation, lab_real.tool_yaw, 3.0, 2.0)
    assert found is None


def test_angle_text_shows_degrees_and_radians() -> None:
    assert angle_text(-math.pi / 4) == "-45.0 deg (-0.785 rad)"


def test_swaps_duplicates_and_the_nearest_slot() -> None:
    grid = {(t, h, k): np.array([0.1 * t, 0.0, 0.03 * h + 0.08 * k]) for t in range(3) for h in range(3)
            for k in (ON, ABOVE)}
    slots = [(0, 0, ON), (0, 1, ON), (0, 2, ON), (1, 1, ON)]
    p = np.array([grid[(0, 0, ON)], grid[(0, 2, ON)], grid[(0, 1, ON)], grid[(1, 1, ON)]]) + 0.0005
    swaps = find_swaps(slots, p, grid, [1, 2], tol_mm=3.0)
    assert swaps[1][0] == 2 and swaps[2][0] == 1 and swaps[1][1] == pytest.approx(math.sqrt(3) * 0.5)
    assert find_swaps(slots, p, grid, [0], tol_mm=3.0) == {}
    assert swap_kind((0, 1, ON), (0, 2, ON)) == "swapped heights"
    assert swap_kind((0, 1, ON), (2, 1, ON)) == "swapped towers"
    assert swap_kind((0, 1, ON), (0, 1, ABOVE)) == "on and above swapped"
    assert swap_kind((0, 1, ON), (2, 0, ABOVE)) == "swapped entries"
    assert nearest_slot(grid[(2, 1, ABOVE)] + 0.001, grid) == ((2, 1, ABOVE), pytest.approx(math.sqrt(3)))
    qs = [[1.0] * 6, [2.0] * 6, [1.0] * 6, [1.0] * 6]
    assert duplicates(slots, qs, [False] * 4) == {0: 2, 2: 0, 3: 0}
    assert duplicates(slots, qs, [False, False, True, False]) == {0: 3, 3: 0}


def test_joint_typo_uses_the_position_when_the_heading_was_recorded_sloppily(lab_real: Station) -> None:
    # The pose was taught 1.5 deg off in heading (about the tool axis, suction point in place), then joint 1 was
    # mistyped by 10 deg: the heading alone would misplace the joint value by 1.5 deg; weighing in the suction
    # point's position (lever 0.3 m about joint 1) brings it within half a degree.
    import pinocchio as pin

    from ur3hanoi.robot.ik import solve_on_branch
    from ur3hanoi.robot.ik_solvers import make_solver

    target = T_world_tcp(lab_real, 1, 1, ON)
    turned = pin.SE3(target.rotation @ pin.utils.rotate("z", math.radians(1.5)), target.translation)
    solver = make_solver("pinocchio", load_ur3(lab_real.tool, lab_real.limits))
    q = solve_on_branch(solver, lab_real.T_world_base.actInv(turned), lab_real.q_home_array).q
    typo_q = q.copy()
    typo_q[0] += math.radians(10.0)
    found = joint_typo(load_ur3(lab_real.tool, lab_real.limits), lab_real.T_world_base, typo_q, target.translation,
                       lab_real.tool_yaw, tol_mm=6.0, tol_deg=2.0)
    assert found is not None and found.joint == 0 and found.explains
    assert math.degrees(found.predicted - q[0]) == pytest.approx(0.0, abs=0.6)


def test_a_pose_in_the_wrong_slot_keeps_the_grid_orientation(lab_real: Station) -> None:
    from ur3hanoi.calibrate.explain import diagnose

    grid = {(t, h, k): T_world_tcp(lab_real, t, h, k).translation for t in range(3) for h in range(3)
            for k in (ON, ABOVE)}
    slots = [(0, 0, ON), (0, 1, ON)]
    q = rt.recorded_q(lab_real, None)
    qs = [q[0, 0, ON], q[0, 2, ON]]  # height 2's entry holds height 3's pose
    p = np.array([grid[(0, 0, ON)], grid[(0, 2, ON)]])
    args = (load_ur3(lab_real.tool, lab_real.limits), lab_real.T_world_base, slots, qs, p)
    rest = (np.array([grid[s] for s in slots]), grid, [1], lab_real.tool_yaw, 3.0, 2.0, ["a", "b"])
    assert diagnose(*args, np.array([0.0, 0.1]), *rest)[1] == "it fits tower 1 height 3 on (0.0 mm): recorded in " \
                                                              "the wrong slot?"
    # The same position with the tool turned 5 deg is no pose of the grid: not "the wrong slot".
    assert "wrong slot" not in diagnose(*args, np.array([0.0, 5.0]), *rest)[1]
