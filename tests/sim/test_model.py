"""ur3hanoi.sim.model: the committed robot files are what the derivation writes, and they load and simulate."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import mujoco
import numpy as np
import pytest

from ur3hanoi.errors import SimulationError
from ur3hanoi.robot.model import Q_HOME_LAB
from ur3hanoi.robot.urdf import JOINT_NAMES, urdf_path
from ur3hanoi.sim import DRIVES, SCENE_XML, UR3_XML, derive_ur3_mjcf, ur3_mesh_sources, warning_counts


def test_ur3_xml_is_up_to_date_with_the_urdf() -> None:
    assert UR3_XML.read_text() == derive_ur3_mjcf(), "run: python -m ur3hanoi.sim"
    for src in ur3_mesh_sources():
        assert (UR3_XML.parent / "assets" / src.name).read_bytes() == src.read_bytes()


def test_module_main_writes_the_committed_files(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "ur3hanoi.sim", str(tmp_path)], capture_output=True, text=True,
                         check=True)
    assert f"wrote {tmp_path / 'ur3.xml'}" in out.stdout
    written = sorted(p.relative_to(tmp_path).as_posix() for p in tmp_path.rglob("*") if p.is_file())
    committed = sorted(p.relative_to(UR3_XML.parent).as_posix() for p in UR3_XML.parent.rglob("*")
                       if p.is_file() and (p.suffix == ".stl" or p.name == "ur3.xml"))
    assert written == committed
    for rel in written:
        assert (tmp_path / rel).read_bytes() == (UR3_XML.parent / rel).read_bytes(), rel


def test_ur3_xml_joints_actuators_keyframe() -> None:
    m = mujoco.MjModel.from_xml_path(str(UR3_XML))
    assert tuple(m.joint(i).name for i in range(m.njnt)) == JOINT_NAMES
    assert m.nu == 6 and all(m.actuator_trntype[i] == mujoco.mjtTrn.mjTRN_JOINT for i in range(6))
    np.testing.assert_allclose(m.key("home").qpos, Q_HOME_LAB, atol=1e-11)
    for name in ("suction_bracket", "suction_cup"):
        assert m.geom(name).contype == 0 and m.geom(name).conaffinity == 0


def test_drive_gains_reach_the_compiled_actuators() -> None:
    m = mujoco.MjModel.from_xml_path(str(UR3_XML))
    for j in JOINT_NAMES:
        drive = DRIVES["size1" if j.startswith("wrist") else "size3"]
        a = m.actuator(j.removesuffix("_joint"))
        assert a.gainprm[0] == drive.kp and -a.biasprm[2] == drive.kv
        assert m.dof_armature[m.joint(j).dofadr[0]] == drive.armature
    assert m.actuator("elbow").forcerange[1] == 28.0 and m.actuator("shoulder_pan").forcerange[1] == 56.0


def test_malformed_urdf_names_the_missing_element(tmp_path: Path) -> None:
    bad = tmp_path / "ur3.urdf"
    bad.write_text(urdf_path().read_text().replace('<axis xyz="0 0 1"/>', "", 1))
    with pytest.raises(SimulationError, match="has no <axis>"):
        derive_ur3_mjcf(bad)


@pytest.mark.parametrize("path", [UR3_XML, SCENE_XML], ids=["ur3", "scene"])
def test_robot_files_simulate_one_second_without_warnings(path: Path) -> None:
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, m.key("home").id)
    mujoco.mj_step(m, d, nstep=round(1.0 / m.opt.timestep))
    assert warning_counts(d) == {}
    np.testing.assert_allclose(d.qpos, Q_HOME_LAB, atol=1e-3)
