"""ur3hanoi.version: the one home of the version. pyproject.toml reads it (no second copy there), the installed
metadata carries it, the package face and the files ur3hanoi writes name it."""

from __future__ import annotations

import importlib.metadata
import tomllib

import ur3hanoi
from tests.support import REPO
from ur3hanoi.version import __version__


def test_pyproject_reads_the_version_from_its_home() -> None:
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    assert "version" not in config["project"] and "version" in config["project"]["dynamic"]
    assert config["tool"]["setuptools"]["dynamic"]["version"] == {"attr": "ur3hanoi.version.__version__"}


def test_the_installed_package_and_the_face_carry_it() -> None:
    assert importlib.metadata.version("ur3hanoi") == __version__
    assert ur3hanoi.__version__ is __version__
