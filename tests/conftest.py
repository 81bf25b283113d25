"""Shared fixtures: the repository root and the two shipped station calibrations."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from ur3hanoi.resources import stations_dir
from ur3hanoi.station import Station, load_station

# Headless offscreen rendering. MuJoCo reads it when first imported, i.e. while the first test module importing
# ur3hanoi.sim is collected: it must be set before any of them.
os.environ.setdefault("MUJOCO_GL", "egl")

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
