"""ur3hanoi.sim.suction: grasping by weld within the lab's radius, and the emulated gripper_input feedback."""

from __future__ import annotations

from dataclasses import replace

import mujoco
import numpy as np
import pytest

from tests.support.sim_helpers import STATIONS
from ur3hanoi.sim import SuctionConfig, SuctionCup, TaskScene, build_task_scene
from ur3hanoi.station.suction_profile import LAB_SIM, REAL, with_levels
from ur3hanoi.tables.ik_table import generate_table


def scene_at_contact(name: str, offset: np.ndarray | None = None) -> TaskScene:
    """Arm at the "on" pose of tower 0 / top block, optionally with that block shifted by ``offset`` [m]."""
    station = STATIONS[name]
    scene = build_task_scene(station, 0, 3)
    q_on = generate_table(station).q[0, 2, 0]
    scene.data.qpos[scene.arm_qadr] = q_on
    scene.data.ctrl[:6] = q_on
    if offset is not None:
        adr = scene.block_qadr[2]
        scene.data.qpos[adr:adr + 3] += offset
    mujoco.mj_forward(scene.model, scene.data)
    return scene


@pytest.mark.parametrize("name", STATIONS)
def test_suction_grasps_without_jump_and_reports_feedback(name: str) -> None:
    scene = scene_at_contact(name)
    cup = SuctionCup(scene, seed=1)
    levels = STATIONS[name].suction  # lab_sim: the course simulator's; lab_real: the `real` profile
    assert not cup.feedback().held and abs(cup.feedback().ain0 - levels.ain0_off) < 0.1
    before = scene.block_pos(2)
    cup.command(True)
    cup.update()
    assert cup.attached == 2
    mujoco.mj_step(scene.model, scene.data, nstep=50)
    assert np.linalg.norm(scene.block_pos(2) - before) < 5e-4  # the weld starts at the current relative pose
    fb = cup.feedback()
    assert fb.digin == 1 and abs(fb.ain0 - levels.ain0_held) < 0.1
    cup.command(False)
    fb = cup.feedback()
    assert fb.digin == 0 and abs(fb.ain0 - levels.ain0_off) < 0.1 and cup.attached is None


@pytest.mark.parametrize(("dist", "grasped"), [(0.009, True), (0.011, False)])
def test_grasp_radius_is_measured_from_the_contact_suction_point(dist: float, grasped: bool) -> None:
    scene = scene_at_contact("lab_sim", offset=np.array([dist, 0.0, 0.0]))
    cup = SuctionCup(scene)
    cup.command(True)
    cup.update()
    assert (cup.attached == 2) is grasped
    fb = cup.feedback()
    assert fb.held is grasped and abs(fb.ain0 - (1.9 if grasped else 1.45)) < 0.05


def test_lost_block_reads_as_not_held_while_suction_stays_on() -> None:
    cup = SuctionCup(scene_at_contact("lab_sim"), SuctionConfig(ain_noise=0.0))
    cup.command(True)
    cup.update()
    assert cup.feedback().held
    assert cup.lose_block() == 2
    fb = cup.feedback()
    assert cup.on and not fb.held and fb.ain0 == 1.45


def test_disabled_grasp_picks_nothing_up() -> None:
    cup = SuctionCup(scene_at_contact("lab_sim"))
    cup.grasp_enabled = False  # what the executor does while halting
    cup.command(True)
    cup.update()
    assert cup.attached is None and not cup.feedback().held


def test_seeded_noise_is_reproducible_and_seed_dependent() -> None:
    def ain0(seed: int) -> list[float]:
        cup = SuctionCup(scene_at_contact("lab_sim"), seed=seed)
        return [cup.feedback().ain0 for _ in range(5)]

    assert ain0(3) == ain0(3)
    assert ain0(3) != ain0(4)
    assert max(abs(v - 1.05) for v in ain0(3)) < 0.05  # 0.01 V noise around the suction-off level


def test_profiles_set_the_levels_of_every_state() -> None:
    """held / cup free / off read the profile's DIGIN and AIN0 (noise off: exactly), for a named and a custom one."""
    custom = with_levels(REAL, {"ain0_held": 3.1, "digin_held": 3, "digin_free": 2})
    assert custom.name == "custom"
    for profile in (LAB_SIM, REAL, custom):
        cup = SuctionCup(scene_at_contact("lab_sim"), SuctionConfig(profile=profile, ain_noise=0.0))
        off = cup.feedback()
        cup.command(True)
        free = cup.feedback()
        cup.update()
        held = cup.feedback()
        assert (held.digin, held.ain0) == (profile.digin_held, profile.ain0_held)
        assert (free.digin, free.ain0) == (profile.digin_free, profile.ain0_free)
        assert (off.digin, off.ain0) == (profile.digin_off, profile.ain0_off)
    assert not SuctionCup(scene_at_contact("lab_sim"), SuctionConfig(profile=custom)).feedback().held


def test_the_cup_reads_the_station_profile_by_default() -> None:
    station = replace(STATIONS["lab_sim"], suction=REAL)
    scene = build_task_scene(station, 0, 3)
    cup = SuctionCup(scene, seed=2)
    assert cup.profile == REAL
    samples = np.array([cup.feedback().ain0 for _ in range(2000)])
    # The profile's noise: mean within 4 standard errors, standard deviation within 10 %.
    assert abs(samples.mean() - REAL.ain0_off) < 4 * REAL.ain0_noise / np.sqrt(len(samples))
    assert abs(samples.std() - REAL.ain0_noise) < 0.1 * REAL.ain0_noise


@pytest.mark.parametrize("threshold", [1.75, 1.8, 1.95, 2.0])
def test_real_profile_separates_every_public_threshold(threshold: float) -> None:
    """Programs written on real robots decide "missing" by AIN0 < t, t in 1.75..2.0 V: with the real profile a held
    block reads above every t and a free cup below it, in 20,000 noisy samples; with lab_sim a held block reads
    below t = 1.95 and 2.0 (the false halt real-robot programs hit on the course simulator's levels)."""
    rng = np.random.default_rng(7)
    held = REAL.ain0_held + rng.normal(0.0, REAL.ain0_noise, 20_000)
    free = REAL.ain0_free + rng.normal(0.0, REAL.ain0_noise, 20_000)
    assert held.min() > threshold > free.max()
    sim_held = LAB_SIM.ain0_held + rng.normal(0.0, LAB_SIM.ain0_noise, 20_000)
    assert bool(sim_held.max() < threshold) is (threshold > 1.9)
