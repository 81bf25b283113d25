"""MuJoCo execution: robot derivation, frames, scene, suction feedback, full solves, fault handling, CLI."""

from __future__ import annotations

import dataclasses
import itertools
import json
import math
import os
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "egl")  # headless offscreen rendering; read when mujoco is first imported

import mujoco
import numpy as np
import pytest

from ur3hanoi import cli
from ur3hanoi.grid import block_center_world
from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import Phase
from ur3hanoi.resources import stations_dir
from ur3hanoi.robot import JOINT_NAMES, Q_HOME_LAB, load_ur3
from ur3hanoi.sim import (
    SCENE_XML,
    UR3_XML,
    Faults,
    SimResult,
    SuctionCup,
    block_name,
    build_task_scene,
    derive_ur3_mjcf,
    make_plan,
    run_plan,
    simple_plan,
    ur3_mesh_sources,
    warning_counts,
)
from ur3hanoi.station import load_station
from ur3hanoi.table import generate_table

REPO = Path(__file__).resolve().parents[1]
STATIONS = {name: load_station(stations_dir() / f"{name}.yaml") for name in ("lab_sim", "lab_real")}
PAIRS = list(itertools.permutations(range(3), 2))
MAX_TRACKING_RAD = math.radians(0.5)


@pytest.fixture(scope="module")
def plans() -> dict:
    """The planner's plan per (station, start, end), computed once (planning dominates the runtime)."""
    cache: dict = {}

    def get(name: str, start: int, end: int):
        key = (name, start, end)
        if key not in cache:
            cache[key] = make_plan(STATIONS[name], start, end, 3)
        return cache[key]

    return get  # type: ignore[return-value]


@pytest.fixture(scope="module")
def solved(plans) -> dict[tuple[str, int, int], SimResult]:
    return {(name, s, e): run_plan(plans(name, s, e)) for name in STATIONS for s, e in PAIRS}


# ------------------------------------------------------------------------------------------------- robot files


def test_ur3_xml_is_up_to_date_with_the_urdf() -> None:
    assert UR3_XML.read_text() == derive_ur3_mjcf(), "run: python -m ur3hanoi.sim"
    for src in ur3_mesh_sources():
        assert (UR3_XML.parent / "assets" / src.name).read_bytes() == src.read_bytes()


def test_ur3_xml_joints_actuators_keyframe() -> None:
    m = mujoco.MjModel.from_xml_path(str(UR3_XML))
    assert tuple(m.joint(i).name for i in range(m.njnt)) == JOINT_NAMES
    assert m.nu == 6 and all(m.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT for i in range(6))
    np.testing.assert_allclose(m.key("home").qpos, Q_HOME_LAB, atol=1e-11)
    for name in ("suction_bracket", "suction_cup"):
        assert m.geom(name).contype == 0 and m.geom(name).conaffinity == 0


@pytest.mark.parametrize("path", [UR3_XML, SCENE_XML], ids=["ur3", "scene"])
def test_robot_files_simulate_one_second_without_warnings(path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    mujoco.mj_step(m, d, nstep=round(1.0 / m.opt.timestep))
    assert warning_counts(d) == {}
    np.testing.assert_allclose(d.qpos, Q_HOME_LAB, atol=1e-3)


# ------------------------------------------------------------------------------------------------- task scene


@pytest.mark.parametrize("name", STATIONS)
def test_tcp_site_equals_pinocchio_fk_in_world(name: str) -> None:
    st = STATIONS[name]
    scene = build_task_scene(st, 0, 3)
    robot = load_ur3(st.tool, st.limits)
    rng = np.random.default_rng(7)
    for _ in range(200):
        q = rng.uniform(-math.pi, math.pi, 6)
        scene.data.qpos[scene.arm_qadr] = q
        mujoco.mj_kinematics(scene.model, scene.data)
        T = st.T_world_base * robot.fk(q, "tcp")
        S = scene.site_pose()
        assert np.linalg.norm(S.translation - T.translation) < 1e-6
        assert np.linalg.norm(S.rotation - T.rotation) < 1e-6


@pytest.mark.parametrize("name", STATIONS)
@pytest.mark.parametrize("start", range(3))
def test_task_scene_spawns_blocks_and_settles_without_warnings(name: str, start: int) -> None:
    st = STATIONS[name]
    scene = build_task_scene(st, start, 3)
    m, d = scene.model, scene.data
    for b in range(3):
        np.testing.assert_allclose(scene.block_pos(b), block_center_world(st, start, b), atol=1e-12)
    d.ctrl[:6] = st.q_home
    mujoco.mj_step(m, d, nstep=500)
    assert warning_counts(d) == {}
    for b in range(3):  # resting blocks stay put (stacks stand; soft contacts sink ~0.25 mm each)
        np.testing.assert_allclose(scene.block_pos(b), block_center_world(st, start, b), atol=1e-3)
    np.testing.assert_allclose(scene.arm_q(), st.q_home, atol=1e-3)
    colours = [m.geom(f"{block_name(b)}_geom").rgba for b in range(3)]
    assert colours[0][1] > colours[0][0] and colours[2][0] > colours[2][1]  # green bottom, red top


def test_removed_block_flat_leaves_slot_empty_stacked_compacts() -> None:
    flat = build_task_scene(STATIONS["lab_sim"], 1, 3, removed=0)
    assert sorted(flat.block_body) == [1, 2]
    np.testing.assert_allclose(flat.block_pos(1), block_center_world(STATIONS["lab_sim"], 1, 1))
    stacked = build_task_scene(STATIONS["lab_real"], 1, 3, removed=0)
    np.testing.assert_allclose(stacked.block_pos(1), block_center_world(STATIONS["lab_real"], 1, 0))
    np.testing.assert_allclose(stacked.block_pos(2), block_center_world(STATIONS["lab_real"], 1, 1))


# ----------------------------------------------------------------------------------------------------- suction


def _scene_at_contact(name: str, offset: np.ndarray | None = None):
    """Arm at the "on" pose of tower 0 / top block, optionally with that block shifted by ``offset`` [m]."""
    st = STATIONS[name]
    scene = build_task_scene(st, 0, 3)
    q_on = generate_table(st).q[0, 2, 0]
    scene.data.qpos[scene.arm_qadr] = q_on
    scene.data.ctrl[:6] = q_on
    if offset is not None:
        adr = scene.block_qadr[2]
        scene.data.qpos[adr:adr + 3] += offset
    mujoco.mj_forward(scene.model, scene.data)
    return scene


@pytest.mark.parametrize("name", STATIONS)
def test_suction_grasps_without_jump_and_reports_feedback(name: str) -> None:
    scene = _scene_at_contact(name)
    cup = SuctionCup(scene, seed=1)
    assert not cup.feedback().held and abs(cup.feedback().ain0 - 1.05) < 0.05
    before = scene.block_pos(2)
    cup.command(True)
    cup.update()
    assert cup.attached == 2
    mujoco.mj_step(scene.model, scene.data, nstep=50)
    assert np.linalg.norm(scene.block_pos(2) - before) < 5e-4  # the weld starts at the current relative pose
    fb = cup.feedback()
    assert fb.digin == 1 and abs(fb.ain0 - 1.9) < 0.05
    cup.command(False)
    fb = cup.feedback()
    assert fb.digin == 0 and abs(fb.ain0 - 1.05) < 0.05 and cup.attached is None


@pytest.mark.parametrize(("dist", "grasped"), [(0.009, True), (0.011, False)])
def test_grasp_radius_is_measured_from_the_contact_suction_point(dist: float, grasped: bool) -> None:
    scene = _scene_at_contact("lab_sim", offset=np.array([dist, 0.0, 0.0]))
    cup = SuctionCup(scene)
    cup.command(True)
    cup.update()
    assert (cup.attached == 2) is grasped
    fb = cup.feedback()
    assert fb.held is grasped and abs(fb.ain0 - (1.9 if grasped else 1.45)) < 0.05


# ------------------------------------------------------------------------------------------------- full solves


@pytest.mark.parametrize("name", STATIONS)
@pytest.mark.parametrize(("start", "end"), PAIRS)
def test_every_start_end_pair_solves(solved, name: str, start: int, end: int) -> None:
    r = solved[(name, start, end)]
    assert r.status == "solved" and r.exit_code == 0 and r.error is None, r.error
    assert r.moves_completed == r.moves_total == 7
    for fb in r.final_blocks:  # verified from the simulation state, 5 mm
        assert (fb.tower, fb.height) == (end, fb.block)
        assert np.linalg.norm(np.subtract(fb.xyz, block_center_world(STATIONS[name], end, fb.block))) <= 0.005
    assert r.at_home_at_end and not r.suction_on_at_end
    assert r.warnings == {}
    assert [e.kind for e in r.feedback_events].count("grasp") == 7


@pytest.mark.parametrize("name", STATIONS)
def test_tracking_error_below_half_a_degree(solved, name: str) -> None:
    worst = max(r.max_tracking_error_rad for (n, _, _), r in solved.items() if n == name)
    assert worst < MAX_TRACKING_RAD, f"{math.degrees(worst):.3f} deg"


def test_tracking_error_on_an_independent_smooth_plan() -> None:
    r = run_plan(simple_plan(STATIONS["lab_sim"], 0, 2, 3))
    assert r.status == "solved" and r.max_tracking_error_rad < math.radians(0.25)


# ---------------------------------------------------------------------------------------------------- faults


def _expected_after(moves, n_done: int, start: int, removed: int | None) -> dict[int, tuple[int, int]]:
    """Slots of the blocks after the first ``n_done`` moves (flat layout: heights are fixed rows)."""
    where = {b: (start, b) for b in range(3) if b != removed}
    for mv in moves[:n_done]:
        where[mv.block] = (mv.to_tower, mv.to_height)
    return where


@pytest.mark.parametrize("height", [1, 2, 3])
def test_remove_block_halts_before_any_further_placement(plans, height: int) -> None:
    plan = plans("lab_sim", 0, 2)
    r = run_plan(plan, Faults(remove_block=height - 1))
    moves = solve_hanoi(3, 0, 2)
    first_use = next(i for i, m in enumerate(moves) if m.block == height - 1)
    assert r.status == "halted" and r.exit_code == 3
    assert r.fault_move == first_use and r.moves_completed == first_use
    assert r.fault_block == height - 1 and r.fault_tower == 0
    assert not r.suction_on_at_end and r.at_home_at_end
    msg = r.error or ""
    assert f"move {first_use + 1}/7" in msg and f"block {height}" in msg and "tower 1" in msg
    expected = _expected_after(moves, first_use, 0, height - 1)
    assert {fb.block: (fb.tower, fb.height) for fb in r.final_blocks} == expected
    assert r.warnings == {}


def test_remove_block_stacked_halts_at_the_first_pick(plans) -> None:
    r = run_plan(plans("lab_real", 0, 2), Faults(remove_block=0))
    assert r.status == "halted" and r.exit_code == 3 and r.moves_completed == 0 and r.fault_move == 0
    assert not r.suction_on_at_end and r.at_home_at_end


@pytest.mark.parametrize(("name", "move"), [("lab_sim", 1), ("lab_sim", 4), ("lab_real", 7)])
def test_drop_during_move_is_detected_within_one_control_cycle(plans, name: str, move: int) -> None:
    plan = plans(name, 0, 2)
    r = run_plan(plan, Faults(drop_during_move=move - 1))
    assert r.status == "halted" and r.exit_code == 3 and r.fault_move == move - 1
    assert r.detection_latency_s is not None and 0 < r.detection_latency_s <= 1.0 / plan.trajectory.rate_hz
    assert r.moves_completed == move - 1
    assert not r.suction_on_at_end and r.at_home_at_end
    kinds = [e.kind for e in r.feedback_events]
    assert kinds[-2:] == ["drop_injected", "dropped"]
    dropped = next(fb for fb in r.final_blocks if fb.block == plan.moves[move - 1].block)
    assert (dropped.tower, dropped.height) != (plan.moves[move - 1].to_tower, plan.moves[move - 1].to_height)


def test_halt_trajectory_has_no_jump(plans) -> None:
    """Stopping mid-carry decelerates smoothly: the tracking error stays small through the halt."""
    r = run_plan(plans("lab_sim", 0, 2), Faults(drop_during_move=2))
    assert r.max_tracking_error_rad < MAX_TRACKING_RAD


def test_plan_contract_labels_are_used(plans) -> None:
    tr = plans("lab_sim", 0, 2).trajectory
    carrying = np.array([Phase(p).carrying for p in tr.phase])
    assert np.all(tr.suction[carrying]) and np.all(tr.suction[tr.phase == Phase.GRASP_DWELL])


# -------------------------------------------------------------------------------------------------------- CLI


JSON_KEYS = {"status", "exit_code", "moves_completed", "moves_total", "error", "final_blocks", "suction_on_at_end",
             "at_home_at_end", "sim_time_s", "wall_time_s", "realtime_factor", "max_tracking_error_rad",
             "feedback_events"}


def test_cli_solve_json(capsys) -> None:
    code = cli.main(["solve", "--start", "2", "--end", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and set(out) >= JSON_KEYS and out["status"] == "solved" and out["error"] is None
    assert [(b["block"], b["tower"], b["height"]) for b in out["final_blocks"]] == [(1, 3, 1), (2, 3, 2), (3, 3, 3)]


def test_cli_solve_remove_block_json_exit_3(capsys) -> None:
    code = cli.main(["solve", "--start", "1", "--end", "2", "--remove-block", "2", "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 3 and out["status"] == "halted" and out["exit_code"] == 3
    assert "block 2" in out["error"] and "ur3hanoi: error: suction fault" in captured.err
    assert out["suction_on_at_end"] is False and out["at_home_at_end"] is True


def test_cli_solve_without_terminal_needs_start_and_end(capsys, monkeypatch) -> None:
    monkeypatch.setattr("sys.stdin.isatty", lambda: False, raising=False)
    assert cli.main(["solve"]) == 2
    assert "--start and --end are required" in capsys.readouterr().err


def test_cli_prompt_reprompts_on_bad_input(capsys, monkeypatch) -> None:
    answers = iter(["4", "x", "1", "1", "3"])
    monkeypatch.setattr("builtins.input", lambda prompt="": next(answers))
    assert cli._solve_prompt_tower("start", 3) == 0
    assert cli._solve_prompt_tower("end", 3, exclude=0) == 2
    assert capsys.readouterr().out.count("Please just enter") == 3


def test_cli_view_without_display_exits_2(capsys, monkeypatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    assert cli.main(["solve", "--start", "1", "--end", "3", "--view"]) == 2
    assert "no display" in capsys.readouterr().err


def test_cli_rejects_bad_fault_arguments(capsys) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "3", "--remove-block", "4"]) == 2
    assert cli.main(["solve", "--start", "1", "--end", "3", "--drop-during-move", "8"]) == 2
    assert cli.main(["solve", "--start", "1", "--end", "1"]) == 2


def test_offscreen_frames(tmp_path: Path) -> None:
    from ur3hanoi.errors import SimulationError
    from ur3hanoi.sim import OffscreenRecorder

    st = STATIONS["lab_sim"]
    scene = build_task_scene(st, 0, 3)
    try:
        rec = OffscreenRecorder(st, scene.model, frames_dir=tmp_path)
    except SimulationError as exc:
        pytest.skip(str(exc))
    with rec:
        rec(scene.model, scene.data)
    assert (tmp_path / "frame_00000.png").stat().st_size > 1000


def test_seeded_noise_is_reproducible() -> None:
    a = [SuctionCup(_scene_at_contact("lab_sim"), seed=3).feedback().ain0 for _ in range(2)]
    assert a[0] == a[1]
    plan = dataclasses.replace(simple_plan(STATIONS["lab_sim"], 0, 1, 1))
    assert run_plan(plan).status == "solved"
