"""ur3hanoi.sim.scene: the task scene puts the calibrated TCP, table and blocks where the station says."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from tests.support.sim_helpers import STATIONS
from ur3hanoi.errors import SimulationError
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.sim import SceneConfig, block_name, build_task_scene, slot_centers, start_slots, warning_counts
from ur3hanoi.station.grid import block_center_world, table_z


@pytest.mark.parametrize("name", STATIONS)
def test_tcp_site_equals_pinocchio_fk_in_world(name: str) -> None:
    station = STATIONS[name]
    scene = build_task_scene(station, 0, 3)
    robot = load_ur3(station.tool, station.limits)
    rng = np.random.default_rng(7)
    for _ in range(200):
        q = rng.uniform(-math.pi, math.pi, 6)
        scene.data.qpos[scene.arm_qadr] = q
        mujoco.mj_kinematics(scene.model, scene.data)
        T = station.T_world_base * robot.fk(q, "tcp")
        S = scene.site_pose()
        assert np.linalg.norm(S.translation - T.translation) < 1e-6
        assert np.linalg.norm(S.rotation - T.rotation) < 1e-6


@pytest.mark.parametrize("name", STATIONS)
@pytest.mark.parametrize("start", range(3))
def test_task_scene_spawns_blocks_and_settles_without_warnings(name: str, start: int) -> None:
    station = STATIONS[name]
    scene = build_task_scene(station, start, 3)
    m, d = scene.model, scene.data
    for b in range(3):
        np.testing.assert_allclose(scene.block_pos(b), block_center_world(station, start, b), atol=1e-12)
    d.ctrl[:6] = station.q_home
    mujoco.mj_step(m, d, nstep=500)
    assert warning_counts(d) == {}
    for b in range(3):  # resting blocks stay put (stacks stand; soft contacts sink ~0.25 mm each)
        np.testing.assert_allclose(scene.block_pos(b), block_center_world(station, start, b), atol=1e-3)
    np.testing.assert_allclose(scene.arm_q(), station.q_home, atol=1e-3)
    colours = [m.geom(f"{block_name(b)}_geom").rgba for b in range(3)]
    assert colours[0][1] > colours[0][0] and colours[2][0] > colours[2][1]  # green bottom, red top


@pytest.mark.parametrize("name", STATIONS)
def test_table_top_is_the_grid_table_and_covers_every_slot(name: str) -> None:
    station = STATIONS[name]
    scene = build_task_scene(station, 0, 3)
    g = scene.model.geom("table")
    assert g.pos[2] + g.size[2] == pytest.approx(table_z(station), abs=1e-12)
    for xyz in slot_centers(station).reshape(-1, 3):
        assert np.all(np.abs(xyz[:2] - g.pos[:2]) < g.size[:2])


def test_removed_block_flat_leaves_slot_empty_stacked_compacts() -> None:
    flat = build_task_scene(STATIONS["lab_sim"], 1, 3, removed=0)
    assert sorted(flat.block_body) == [1, 2]
    np.testing.assert_allclose(flat.block_pos(1), block_center_world(STATIONS["lab_sim"], 1, 1))
    stacked = build_task_scene(STATIONS["lab_real"], 1, 3, removed=0)
    np.testing.assert_allclose(stacked.block_pos(1), block_center_world(STATIONS["lab_real"], 1, 0))
    np.testing.assert_allclose(stacked.block_pos(2), block_center_world(STATIONS["lab_real"], 1, 1))


@given(n_blocks=st.integers(1, 3), start=st.integers(0, 2), removed=st.one_of(st.none(), st.integers(0, 2)))
def test_start_slots_are_distinct_and_on_the_start_tower(n_blocks: int, start: int, removed: int | None) -> None:
    for station in STATIONS.values():
        slots = start_slots(station, start, n_blocks, removed)
        assert set(slots) == set(range(n_blocks)) - {removed}
        assert {t for t, _ in slots.values()} <= {start}
        heights = [h for _, h in slots.values()]
        assert len(set(heights)) == len(heights) and heights == sorted(heights)  # bottom block lowest
        if station.layout == "flat":
            assert all(h == b for b, (_, h) in slots.items())  # a flat grid keeps every block in its own row
        else:
            assert heights == list(range(len(heights)))  # a stack has no gaps


def test_invalid_block_count_and_timestep_are_rejected() -> None:
    with pytest.raises(SimulationError, match=r"4 blocks is invalid: expected 1\.\.3"):
        build_task_scene(STATIONS["lab_sim"], 0, 4)
    with pytest.raises(SimulationError, match=r"timestep 0\.004 s is too long"):
        build_task_scene(STATIONS["lab_sim"], 0, 3, config=SceneConfig(timestep=0.004))
