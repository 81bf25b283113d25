"""ur3hanoi.sim.dh_model: the UR3e MuJoCo model built with MjSpec from its DH description: same kinematics as the
Pinocchio model (suction site to 1e-9 m), UR's masses, its own primitive visual (no UR3 mesh), and the ur3e_sim
station solves the lab in it."""

from __future__ import annotations

import json
import math

import mujoco
import numpy as np
import pytest

from ur3hanoi import cli
from ur3hanoi.io.resources import robots_dir
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.robot.registry import UR3E
from ur3hanoi.robot.urdf import LINKS
from ur3hanoi.sim import build_task_scene
from ur3hanoi.sim.dh_model import build_dh_robot_spec, compiled_masses
from ur3hanoi.station.calibration import load_station


def test_suction_site_equals_pinocchio_tcp_fk() -> None:
    station = load_station("ur3e_sim")
    assert station.robot == UR3E
    scene = build_task_scene(station, 0, 3)
    robot = load_ur3(station.tool, station.limits, station.robot)
    rng = np.random.default_rng(3)
    for q in rng.uniform(-math.pi, math.pi, (50, 6)):
        scene.data.qpos[scene.arm_qadr] = q
        mujoco.mj_kinematics(scene.model, scene.data)
        T = station.T_world_base * robot.fk(q, "tcp")
        assert np.linalg.norm(scene.site_pose().translation - T.translation) < 1e-9
        assert np.abs(scene.site_pose().rotation - T.rotation).max() < 1e-9


def test_masses_are_urs_and_the_visual_is_not_the_ur3s() -> None:
    assert compiled_masses(UR3E)[1:] == pytest.approx(UR3E.masses, abs=1e-12)
    model = build_dh_robot_spec(UR3E).compile()
    assert model.nmesh == 0  # primitives only
    arm_geoms = [g for g in range(model.ngeom) if model.body(model.geom_bodyid[g]).name in LINKS]
    assert len(arm_geoms) >= 7
    assert all(model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CYLINDER for g in arm_geoms)
    assert list(model.actuator_forcerange[:, 1]) == list(UR3E.torque)


def test_shipped_ur3e_xml_compiles_to_the_built_model() -> None:
    shipped = mujoco.MjModel.from_xml_path(str(robots_dir() / UR3E.mjcf_dir / "ur3e.xml"))
    built = build_dh_robot_spec(UR3E).compile()
    assert (shipped.nbody, shipped.njnt, shipped.ngeom, shipped.nu) == (built.nbody, built.njnt, built.ngeom, built.nu)
    assert np.abs(shipped.body_mass - built.body_mass).max() < 1e-6
    assert np.abs(shipped.body_pos - built.body_pos).max() < 1e-6


def test_ur3e_sim_station_solves_in_mujoco(capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["solve", "--calibration", "ur3e_sim", "--start", "1", "--end", "3", "--json"])
    out = json.loads(capsys.readouterr().out)
    assert code == 0 and out["status"] == "solved", out["error"]
    assert [(b["block"], b["tower"], b["height"]) for b in out["final_blocks"]] == [(1, 3, 1), (2, 3, 2), (3, 3, 3)]
    assert out["suction"]["profile"] == "real"
    assert out["max_tracking_error_rad"] < math.radians(0.5)
