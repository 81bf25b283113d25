"""The package's architecture holds: import-linter's contracts (pyproject.toml) are kept, there are at most nine
layers and eight loose modules, and the contracts catch a planted upward import (also one through the package face
``ur3hanoi``, which stands on every layer) and a planted cycle.

import-linter reads every import statement (module level, ``if TYPE_CHECKING:``, inside functions): a lazy or
typing-only import only delays a dependency, it does not remove it.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from tests.support import REPO

PACKAGE = REPO / "ur3hanoi"
LINT_IMPORTS = Path(sys.executable).parent / "lint-imports"


def _contracts() -> list[dict[str, object]]:
    config = tomllib.loads((REPO / "pyproject.toml").read_text(encoding="utf-8"))
    contracts: list[dict[str, object]] = config["tool"]["importlinter"]["contracts"]
    return contracts


def _lint(root: Path) -> subprocess.CompletedProcess[str]:
    """``lint-imports`` with the project's contracts on the package copy under ``root``."""
    env = dict(os.environ, PYTHONPATH=str(root))
    return subprocess.run([str(LINT_IMPORTS), "--config", str(REPO / "pyproject.toml"), "--no-cache"], cwd=root,
                          env=env, capture_output=True, text=True, timeout=120, check=False)


def test_the_contracts_are_kept() -> None:
    result = _lint(REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    assert f"{len(_contracts())} kept, 0 broken" in result.stdout


def test_at_most_nine_layers_and_eight_loose_modules() -> None:
    (layers,) = (c["layers"] for c in _contracts() if c["id"] == "layers")
    assert isinstance(layers, list) and len(layers) <= 9, layers
    loose = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(loose) <= 8, loose
    folders = {f"ur3hanoi.{p.name}" for p in PACKAGE.iterdir() if (p / "__init__.py").exists()}
    layered = [name.strip() for layer in layers for name in layer.split("|")]  # type: ignore[union-attr]
    assert sorted(layered) == sorted(folders), "every folder of the package is a layer (or a sibling in one), whole"


@pytest.fixture(scope="module")
def package_copy(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("copy")
    shutil.copytree(PACKAGE, root / "ur3hanoi", ignore=shutil.ignore_patterns("__pycache__", "*.stl", "*.xml"))
    return root


def _planted(package_copy: Path, module: str, line: str) -> subprocess.CompletedProcess[str]:
    path = package_copy / "ur3hanoi" / module
    original = path.read_text(encoding="utf-8")
    try:
        path.write_text(original + f"\n{line}\n", encoding="utf-8")
        return _lint(package_copy)
    finally:
        path.write_text(original, encoding="utf-8")


def test_the_copy_is_linted_and_kept(package_copy: Path) -> None:
    result = _lint(package_copy)
    assert result.returncode == 0, result.stdout + result.stderr


@pytest.mark.parametrize(("module", "line", "contract"), [
    ("robot/model.py", "import ur3hanoi.plan.types", "Layers"),  # the arm reaching up to the planner
    ("io/cache.py", "from ur3hanoi.robot.model import Ur3Model", "Layers"),
    ("hanoi.py", "import ur3hanoi.station.grid", "loose modules"),
    ("io/cache.py", "from ur3hanoi import __version__", "Layers"),  # the package face stands on every layer
    ("version.py", "import ur3hanoi", "loose modules"),
    ("interface/ros2/dds.py", "from ur3hanoi.interface.ros1 import env", "ROS 1 and ROS 2"),
    ("interface/urdriver/station.py", "from ur3hanoi.interface.course import controller", "The two protocols' cores"),
    ("interface/common/inbox.py", "import ur3hanoi.interface.course.station", "Inside interface"),
    ("plan/types.py", "from ur3hanoi.plan.motion import ruckig", "Inside plan"),
    ("robot/dh.py", "def _f():\n    from ur3hanoi.robot.model import Ur3Model", "Inside robot"),  # a bounce back
    ("station/calibration.py", "def _f():\n    from ur3hanoi.station import grid", "No import cycles"),
])
def test_a_planted_import_breaks_its_contract(package_copy: Path, module: str, line: str, contract: str) -> None:
    result = _planted(package_copy, module, line)
    assert result.returncode == 1, result.stdout + result.stderr
    broken = result.stdout[result.stdout.index("Broken contracts"):]
    assert contract in broken, broken
