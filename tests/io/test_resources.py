"""ur3hanoi.io.resources: the shipped robot folder and stations, found inside the package, addressable by name."""

from __future__ import annotations

from pathlib import Path

import pytest

import ur3hanoi
from ur3hanoi.errors import CalibrationError
from ur3hanoi.io.resources import TAUGHT_EXAMPLE, robot_dir, station_file, station_names, stations_dir
from ur3hanoi.station.calibration import load_station


def test_data_lives_inside_the_package_not_the_working_directory() -> None:
    package = Path(ur3hanoi.__file__).parent
    assert robot_dir().is_relative_to(package) and stations_dir().is_relative_to(package)
    for name in ("ur3.xml", "scene.xml", "LICENSE", "README.md", "CHANGELOG.md"):
        assert (robot_dir() / name).is_file(), name
    assert sorted(p.name for p in (robot_dir() / "assets").glob("*.stl")) == [
        "base.stl", "forearm.stl", "shoulder.stl", "upperarm.stl", "wrist1.stl", "wrist2.stl", "wrist3.stl"]


def test_shipped_stations_are_named_and_the_example_taught_file_is_not_one() -> None:
    assert station_names() == ("lab_real", "lab_sim", "ur3e_sim")
    assert (stations_dir() / TAUGHT_EXAMPLE).is_file() and "taught_example" not in station_names()


def test_a_name_resolves_to_the_shipped_file_and_a_path_stays_a_path(tmp_path: Path,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    assert station_file("lab_sim") == stations_dir() / "lab_sim.yaml"
    mine = tmp_path / "lab_sim.yaml"  # a user's file of the same name, given as a path, is the user's
    assert station_file(str(mine)) == mine and station_file(mine) == mine
    monkeypatch.chdir(tmp_path)
    assert load_station("lab_sim").name == "lab_sim"  # from any working directory


def test_an_unknown_station_lists_the_shipped_names() -> None:
    with pytest.raises(CalibrationError) as info:
        load_station("lab_simm")
    assert "lab_real, lab_sim" in str(info.value) and "lab_simm" in str(info.value)
