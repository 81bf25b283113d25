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


SHARED_SCOPES = ("module", "package", "class")


@pytest.hookimpl(tryfirst=True)  # before xdist reads the groups
def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under ``--dist loadgroup`` (make test's wall-clock phase) the tests of one module that share a module-scoped
    fixture (a station, a built wheel, a ROS 2 environment's graph) go to one worker, so that it starts once; one
    group per value of a parametrised one (Jazzy and Kilted may run side by side). Other tests go one by one."""
    for item in items:
        info = getattr(item, "_fixtureinfo", None)
        if info is None or item.get_closest_marker("xdist_group") is not None:
            continue
        shared = sorted(name for name, defs in info.name2fixturedefs.items() if defs[-1].scope in SHARED_SCOPES)
        if shared:
            params = getattr(getattr(item, "callspec", None), "params", {})
            values = [f"{name}={params[name]}" for name in shared if name in params]
            item.add_marker(pytest.mark.xdist_group("|".join([item.nodeid.split("::", 1)[0], *values])))
    if getattr(config.option, "loadgroup", False):  # set in the workers of --dist loadgroup
        _group_ids(items)


def _group_ids(items: list[pytest.Item]) -> None:
    """xdist's loadgroup sends the tests whose node id ends in ``@GROUP`` to one worker. xdist 3.8 writes that suffix
    into ``item._nodeid``, which pytest 9.2's structured node ids no longer read: grouping silently stops
    (https://github.com/pytest-dev/pytest-xdist/issues/1386). Until xdist writes it where pytest reads it (its pull
    request 1388 does what this does), the suffix goes into the structured id; on a pytest without one, xdist's own
    suffix works."""
    try:
        from _pytest.nodeid import NodeId
    except ImportError:
        return
    for item in items:
        groups = sorted({str(m.args[0] if m.args else m.kwargs.get("name", "default"))
                         for m in item.iter_markers("xdist_group")})
        if groups and isinstance(getattr(item, "_id", None), NodeId) and "@" not in item.nodeid:
            item._id = NodeId.parse(f"{item.nodeid}@{'_'.join(groups)}")


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
