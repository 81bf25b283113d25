"""The package installs like a package: a wheel, installed into a fresh virtual environment, runs the main job.

This is what a new user does: ``pip wheel .``, install that wheel (with ``requirements.lock`` as constraints) into
a new environment, go to an empty folder outside the checkout, run ``ur3hanoi solve`` and ``ur3hanoi tables``. It
fails when the robot model or the shipped stations are missing from the wheel, or when the code looks for them
next to the source tree or in the working directory.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import venv
import zipfile
from pathlib import Path

import numpy as np
import pytest
import yaml

from tests.conftest import REPO
from ur3hanoi.interface.urdriver.facts import MSG_TEXTS
from ur3hanoi.io.resources import robot_dir, station_names, stations_dir

pytestmark = pytest.mark.packaging


def _run(cmd: list[str | Path], cwd: Path, timeout: float, env: dict[str, str] | None = None
         ) -> subprocess.CompletedProcess[str]:
    result = subprocess.run([str(c) for c in cmd], cwd=cwd, capture_output=True, text=True, timeout=timeout,
                            env=env)
    assert result.returncode == 0, f"{cmd} exited {result.returncode}:\n{result.stdout}\n{result.stderr}"
    return result


def _source_copy(dest: Path) -> Path:
    """The checkout's files as git sees them (tracked + new, not ignored): no stale ``build/`` or egg-info."""
    listed = _run(["git", "ls-files", "-z", "--cached", "--others", "--exclude-standard"], cwd=REPO, timeout=60)
    for name in filter(None, listed.stdout.split("\0")):
        src = REPO / name
        if src.is_file():
            (dest / name).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, dest / name)
    return dest


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    src = _source_copy(tmp_path_factory.mktemp("src"))
    out = tmp_path_factory.mktemp("wheel")
    _run([sys.executable, "-m", "pip", "wheel", "-q", "--no-deps", "-w", out, src], cwd=out, timeout=300)
    (path,) = out.glob("ur3hanoi-*.whl")
    return path


def test_wheel_carries_the_robot_folder_the_stations_and_the_message_texts(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    robot = f"ur3hanoi/robot/models/{robot_dir().name}"
    expected = {f"{robot}/{f}" for f in ("ur3.xml", "scene.xml", "LICENSE", "README.md", "CHANGELOG.md")}
    expected |= {f"{robot}/assets/{p.name}" for p in (robot_dir() / "assets").glob("*.stl")}
    expected |= {f"ur3hanoi/station/shipped/{n}.yaml" for n in station_names()}
    expected |= {"ur3hanoi/py.typed"}
    expected |= {f"ur3hanoi/interface/urdriver/msg_texts/{p.relative_to(MSG_TEXTS)}" for p in MSG_TEXTS.rglob("*")
                 if p.is_file()}  # the UR driver's message texts (both ROS bindings build their classes from them)
    assert len(expected) > 20
    assert expected <= names, f"missing from the wheel: {sorted(expected - names)}"


def test_installed_wheel_runs_the_main_job_from_an_empty_folder(wheel: Path, tmp_path: Path) -> None:
    env_dir = tmp_path / "venv"
    venv.create(env_dir, with_pip=True)
    py = env_dir / "bin" / "python"
    # Without PYTHONPATH also for pip: a checkout on it (its egg-info) would pass for the installed package.
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV")}
    _run([py, "-m", "pip", "install", "-q", "--disable-pip-version-check", "-c", REPO / "requirements.lock",
          wheel], cwd=tmp_path, timeout=600, env=env)
    work = tmp_path / "empty"
    work.mkdir()
    exe = env_dir / "bin" / "ur3hanoi"

    solved = _run([exe, "solve", "--start", "1", "--end", "3"], cwd=work, timeout=300, env=env)
    assert solved.stdout.startswith("solved: 7/7 moves"), solved.stdout

    _run([exe, "tables", "lab_sim", "--key", "sim_pos", "-o", "lab2_data.yaml"], cwd=work, timeout=120, env=env)
    written = yaml.safe_load((work / "lab2_data.yaml").read_text())
    shipped = yaml.safe_load((REPO / "tables" / "lab2_data.yaml").read_text())
    # The same table within the IK's accuracy [rad]: another CPU or Python differs in the last bits (~1e-15).
    for key in ("sim_pos", "block_xy_pos"):
        np.testing.assert_allclose(np.array(written[key], dtype=float), np.array(shipped[key], dtype=float),
                                   rtol=0.0, atol=1e-9, err_msg=key)
    left = {p.name for p in work.iterdir()}  # no temporary files; a lock file beside the table is allowed
    assert "lab2_data.yaml" in left and left <= {"lab2_data.yaml", ".lab2_data.yaml.lock", "lab2_data.yaml.lock"}

    # The installed package finds its data inside site-packages, not in this checkout.
    where = _run([py, "-c", "from ur3hanoi.io.resources import stations_dir; print(stations_dir())"], cwd=work,
                 timeout=60, env=env).stdout.strip()
    assert Path(where).is_relative_to(env_dir) and not Path(where).is_relative_to(stations_dir().parent)
