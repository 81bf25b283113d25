"""Files shipped inside the package: the MuJoCo UR3 robot folder and the station calibrations.

Everything is found beside this module, in the package's own folder, never through the working directory, so an
installed wheel finds the same files as a checkout. MuJoCo and the YAML loader need real files, so the package must
be installed unzipped (what pip does for wheels); for such a package :func:`importlib.resources.files` is this same
folder, and importing it would cost every command that reads a station 4-5 ms (it loads zipfile and threading).

Shipped stations are addressable by name wherever a calibration file is accepted: ``lab_sim`` (the course's
flat Gazebo layout) and ``lab_real`` (an example stacked station); see ``ur3hanoi/station/shipped/README.md``.
"""

from __future__ import annotations

from pathlib import Path

ROBOT_NAME = "universal_robots_ur3"
"""The robot folder (Menagerie naming: ``<maker>_<model>``) under ``ur3hanoi/robot/models/``."""

TAUGHT_EXAMPLE = "taught_example.yaml"
"""An example taught-points file shipped beside the stations (not a station)."""


_PACKAGE = Path(__file__).resolve().parent.parent  # ur3hanoi/


def _package_dir(*parts: str) -> Path:
    return _PACKAGE.joinpath(*parts)


def robot_dir() -> Path:
    """The MuJoCo robot folder: ``ur3.xml``, ``scene.xml``, ``assets/``, LICENSE, README, CHANGELOG."""
    return _package_dir("robot", "models", ROBOT_NAME)


def robots_dir() -> Path:
    """The folder of the robot model folders (``universal_robots_ur3``, ``universal_robots_ur3e``)."""
    return _package_dir("robot", "models")


def stations_dir() -> Path:
    """The folder of the shipped station calibrations (and the example taught-points file)."""
    return _package_dir("station", "shipped")


def station_names() -> tuple[str, ...]:
    """Names of the shipped stations, sorted (``("lab_real", "lab_sim", "ur3e_sim")``)."""
    return tuple(sorted(p.stem for p in stations_dir().glob("*.yaml") if p.name != TAUGHT_EXAMPLE))


def is_station_name(ref: str | Path) -> bool:
    """True when ``ref`` names a shipped station (a bare name: no folder, no file extension)."""
    return isinstance(ref, str) and ref in station_names()


def station_file(ref: str | Path) -> Path:
    """The calibration file for ``ref``: a shipped station name (``lab_sim``) or a path, returned unchanged.

    A bare name wins over a file of that name in the working directory only when it has no extension and no
    folder, which no calibration file path has in practice (they end in ``.yaml``).
    """
    if is_station_name(ref):
        return stations_dir() / f"{ref}.yaml"
    return Path(ref)
