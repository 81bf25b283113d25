"""Shared fixtures: the repository root and the two shipped station calibrations."""

from __future__ import annotations

import atexit
import contextlib
import os
import shutil
import tempfile
from pathlib import Path

import pytest

from tests.support import reaper
from tests.support.xdist_groups import pytest_collection_modifyitems  # noqa: F401  (make test: one worker a module)
from ur3hanoi.errors import SimulationError
from ur3hanoi.io.resources import stations_dir
from ur3hanoi.opengl import use_platform
from ur3hanoi.station.calibration import Station, load_station

# The stations and clients the tests start are killed when this pytest process is gone, even by SIGKILL
# (tests/support/reaper.py).
reaper.start(os.getpid())

# Offscreen rendering with the OpenGL platform the commands would choose on this machine (the display's, else EGL,
# else OSMesa; a MUJOCO_GL set by the caller is kept). MuJoCo reads MUJOCO_GL when first imported, i.e. while the
# first test module importing ur3hanoi.sim is collected: it must be set before any of them. The commands the tests
# run inherit it, already tried (ur3hanoi.opengl.VERIFIED): they try nothing again. With no platform, the tests that
# render fail with the one line that says why.
with contextlib.suppress(SimulationError):
    use_platform()

# The suite has a user cache of its own (ur3hanoi.io.cache: collision geometry, plan connections), so that an entry left
# in the user's cache by another version can never change a result, and the tests leave nothing behind there. The
# throwaway rclpy environments (tests/support/rclpy_support.py) stay in the user's real cache: they take minutes to
# build.
os.environ.setdefault("UR3HANOI_RCLPY_CACHE", os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache"))
_SUITE_CACHE = tempfile.mkdtemp(prefix="ur3hanoi-test-cache-")
os.environ["XDG_CACHE_HOME"] = _SUITE_CACHE
atexit.register(shutil.rmtree, _SUITE_CACHE, True)

REPO = Path(__file__).resolve().parents[1]
LAB_SIM = stations_dir() / "lab_sim.yaml"
LAB_REAL = stations_dir() / "lab_real.yaml"
STATION_FILES = {"lab_sim": LAB_SIM, "lab_real": LAB_REAL}


@pytest.fixture(scope="session")
def repo() -> Path:
    return REPO


@pytest.fixture(scope="session")
def lab_sim() -> Station:
    return load_station(LAB_SIM)


@pytest.fixture(scope="session")
def lab_real() -> Station:
    return load_station(LAB_REAL)


@pytest.fixture(scope="session", params=sorted(STATION_FILES))
def shipped_station(request: pytest.FixtureRequest) -> Station:
    return load_station(STATION_FILES[request.param])
