"""ur3hanoi.sim.world: the movej world stepped in world time (no ROS): settling for the lab's wait, suction, blocks,
faults."""

from __future__ import annotations

import pytest

from ur3hanoi.errors import SimulationError
from ur3hanoi.sim.config import SimConfig
from ur3hanoi.sim.world import MoveJWorld
from ur3hanoi.tables.ik_table import generate_table

TOL = 5e-4  # [rad] the lab's move_arm tolerance


def go(world: MoveJWorld, q, io_0: bool = False, v: float = 4.0, a: float = 4.0, rest_s: float = 0.3):
    """Run one movej and rest_s [s] after it; returns (settle time after the profile [s], error after rest [rad])."""
    world.begin(q, v, a, io_0)
    while world.moving:
        world.step()
    t_end, settle = world.time, None
    for _ in range(round(rest_s / world.config.period_s)):
        world.step()
        err = world.error_to_target()
        if settle is None and err <= TOL:
            settle = world.time - t_end
        if settle is not None:
            assert err <= TOL, f"left the tolerance after settling: {err:.2e} rad"
    return settle, world.error_to_target()


@pytest.mark.parametrize("name", ["lab_sim", "lab_real"])
def test_every_table_pose_settles_within_the_labs_tolerance(name, request):
    station = request.getfixturevalue(name)
    world = MoveJWorld(station, 0, station.n_heights)
    Q = generate_table(station).q
    worst_settle, worst_err = 0.0, 0.0
    for t in range(station.n_towers):
        for h in range(station.n_heights):
            for q in (Q[t, h, 1], Q[t, h, 0], Q[t, h, 1]):
                settle, err = go(world, q)
                assert settle is not None, f"tower {t} height {h}: never within {TOL} rad (error {err:.2e})"
                worst_settle, worst_err = max(worst_settle, settle), max(worst_err, err)
    assert worst_settle < 0.1  # [s] after the profile's end
    assert worst_err < 0.2 * TOL  # at rest the published angles are far inside the lab's tolerance


def test_suction_grasps_holds_and_releases_with_the_courses_voltages(lab_sim):
    world = MoveJWorld(lab_sim, 0, 3)
    Q = generate_table(lab_sim).q
    assert world.feedback().digin == 0 and world.feedback().ain0 == pytest.approx(1.05, abs=0.05)
    go(world, Q[0, 2, 1])
    go(world, Q[0, 2, 1], io_0=True)
    assert world.feedback().digin == 0 and world.feedback().ain0 == pytest.approx(1.45, abs=0.05)
    go(world, Q[0, 2, 0], io_0=True)
    fb = world.feedback()
    assert (fb.digin, world.holding) == (1, 2) and fb.ain0 == pytest.approx(1.9, abs=0.05)
    go(world, Q[0, 2, 1], io_0=True)
    settle, err = go(world, Q[2, 0, 1], io_0=True)  # carry at full speed: the block stays on the cup
    assert world.holding == 2 and settle is not None and err < TOL
    go(world, Q[2, 0, 0], io_0=True)
    go(world, Q[2, 0, 0], io_0=False)
    go(world, Q[2, 0, 1])
    assert world.holding is None and world.feedback().digin == 0
    slots = {b.block: (b.tower, b.height) for b in world.blocks()}
    assert slots == {0: (0, 0), 1: (0, 1), 2: (2, 0)}
    kinds = [e.kind for e in world.events]
    assert kinds == ["spawn", "suction_on", "grasp", "suction_off", "release"]


def test_spawn_and_remove_blocks(lab_sim, lab_real):
    world = MoveJWorld(lab_sim, 0, 3, removed=1)
    assert {b.block: (b.tower, b.height) for b in world.blocks()} == {0: (0, 0), 1: (None, None), 2: (0, 2)}
    world.spawn(1)
    assert {b.block: (b.tower, b.height) for b in world.blocks()} == {0: (1, 0), 1: (1, 1), 2: (1, 2)}
    assert world.remove(0) == "removed"
    assert world.remove(0) == "absent"
    assert {b.block: b.tower for b in world.blocks()}[0] is None
    for _ in range(100):  # parked blocks stay parked, the others stay in their slots
        world.step()
    assert {b.block: (b.tower, b.height) for b in world.blocks()} == {0: (None, None), 1: (1, 1), 2: (1, 2)}
    assert [e.as_dict()["kind"] for e in world.events][-2:] == ["spawn", "removed"]
    # Stacked: blocks above a removed one rest a level lower, like ur3hanoi solve's spawn.
    stacked = MoveJWorld(lab_real, 2, 3, removed=0)
    assert {b.block: (b.tower, b.height) for b in stacked.blocks()} == {0: (None, None), 1: (2, 0), 2: (2, 1)}
    with pytest.raises(SimulationError, match=r"tower 4 is invalid: expected 1\.\.3"):
        world.spawn(3)
    with pytest.raises(SimulationError, match=r"block 4 is invalid: expected 1\.\.3"):
        world.remove(3)


def test_removing_the_held_block_drops_it(lab_sim):
    world = MoveJWorld(lab_sim, 0, 3)
    Q = generate_table(lab_sim).q
    go(world, Q[0, 2, 0])
    go(world, Q[0, 2, 0], io_0=True)
    assert world.holding == 2
    assert world.remove(2) == "dropped"
    go(world, Q[0, 2, 1], io_0=True)
    assert world.holding is None and world.feedback().digin == 0 and world.suction_on


def test_drop_on_grasp_loses_the_block_early_in_the_next_motion(lab_sim):
    world = MoveJWorld(lab_sim, 0, 3, config=SimConfig(drop_delay_s=0.2), drop_on_grasp=1)
    Q = generate_table(lab_sim).q
    for grasp, (t, h) in enumerate([(0, 2), (0, 1)]):
        go(world, Q[t, h, 0], io_0=False)
        go(world, Q[t, h, 0], io_0=True)
        world.begin(Q[t, h, 1], 4.0, 4.0, True)
        held = []
        while world.moving:
            world.step()
            held.append(world.holding is not None)
        if grasp == 0:
            assert all(held)
        else:  # the second grasp: held for the first 0.2 s of the lift, then lost
            lost_at = held.index(False) * world.config.period_s
            assert 0.19 <= lost_at <= 0.22
        go(world, Q[t, h, 1], io_0=False)
    assert [e.kind for e in world.events if e.kind in ("grasp", "dropped")] == ["grasp", "grasp", "dropped"]


def test_period_must_be_a_multiple_of_the_physics_step(lab_sim):
    with pytest.raises(SimulationError, match=r"control period 0\.003 s is invalid"):
        MoveJWorld(lab_sim, 0, 3, config=SimConfig(period_s=0.003))
