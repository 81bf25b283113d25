"""Where ur3hanoi's UR driver interface gets ``rclpy``: a sourced ROS 2 installation, or ``ur3hanoi ros2-env``.

The official driver's action and services need rclpy on the robot PC's DDS (``../shared/lab/ur-driver-interface.md``
section 4); the course-topic commands never do (Cyclone DDS, :mod:`ur3hanoi.interface.ros2.dds`). Two ways in, the
one-line error says both:

- a sourced ROS 2 installation (``source /opt/ros/jazzy/setup.bash``) whose Python is the project's, with
  ``control_msgs`` and ``ur_msgs`` (the UR driver's packages bring them): its ``PYTHONPATH`` already holds them;
- ``eval "$(ur3hanoi ros2-env)"``: an environment built once in the user cache from PyPI wheels
  (:mod:`ur3hanoi.interface.ros2.rclpy_build`). The lines set ``LD_LIBRARY_PATH`` (the wheels' libraries are found
  only through it, as the wheels' own bootstrap does), ``AMENT_PREFIX_PATH``, ``ROS_DISTRO`` and
  :data:`ENV_VAR`; :func:`import_rclpy` then **appends** the environment's Python folders to ``sys.path``, after the
  project's own, so its NumPy and PyYAML keep precedence (as :mod:`ur3hanoi.interface.ros1.env` does for Debian's
  ROS 1).
"""

from __future__ import annotations

import importlib
import json
import os
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

from ur3hanoi.interface.ros2.errors import RclpyUnavailableError

ENV_VAR = "UR3HANOI_ROS2_ENV"
"""Names the ``ros2-env`` environment a process uses (set by the lines ``ros2-env`` prints)."""

MANIFEST = "manifest.json"
FORMAT = 1

def _this_python() -> str:
    return f"{sys.version_info[0]}.{sys.version_info[1]}"


HINT = ('run eval "$(ur3hanoi ros2-env)" (builds rclpy and the UR messages for this Python once, from PyPI), or '
        f"source a ROS 2 installation built for Python {_this_python()} with the UR driver's control_msgs and ur_msgs")


def read_manifest(root: Path) -> dict[str, object] | None:
    """The manifest of the environment in ``root``, or None where there is none (not built, or a build was cut)."""
    try:
        data = json.loads((root / MANIFEST).read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) and data.get("format") == FORMAT else None


def write_manifest(root: Path, wheels: str, python: str, pins: list[str], packages: dict[str, str]) -> None:
    """Write the manifest last and atomically (rename): a reader sees a complete environment or none."""
    tmp = root / f".{MANIFEST}.{os.getpid()}"
    tmp.write_text(json.dumps({"format": FORMAT, "wheels": wheels, "python": python, "pins": pins,
                               "packages": packages}, indent=1) + "\n")
    os.replace(tmp, root / MANIFEST)


@dataclass(frozen=True)
class RclpyEnv:
    """A complete ``ros2-env`` environment: the wheels' virtual environment and one prefix per message package."""

    root: Path
    wheels: str
    python: str
    packages: tuple[str, ...]

    @classmethod
    def load(cls, root: Path) -> RclpyEnv:
        """The environment in ``root``.

        Raises:
            RclpyUnavailableError: ``root`` holds no complete environment.
        """
        data = read_manifest(root)
        if data is None:
            raise RclpyUnavailableError(f"{root} is not a complete ros2-env environment (no {MANIFEST}): {HINT}")
        packages = data.get("packages")
        return cls(root, str(data["wheels"]), str(data["python"]), tuple(sorted(packages) if isinstance(
            packages, dict) else ()))

    @property
    def python_exe(self) -> Path:
        """The environment's own interpreter (its processes re-execute once with the wheels' library path)."""
        return self.root / "venv" / "bin" / "python"

    def _site(self, prefix: Path) -> Path:
        return prefix / "lib" / f"python{self.python}" / "site-packages"

    @property
    def prefixes(self) -> list[Path]:
        """The message packages' install prefixes, then the wheels' environment (``AMENT_PREFIX_PATH``)."""
        return [*(self.root / "msgs" / p for p in self.packages), self.root / "venv"]

    @property
    def site_dirs(self) -> list[Path]:
        """The Python folders to append to ``sys.path``."""
        return [self._site(p) for p in self.prefixes]

    @property
    def lib_dirs(self) -> list[Path]:
        """The shared-library folders (``LD_LIBRARY_PATH``): every prefix's ``lib`` and the wheels' vendored
        ``ros_*.libs`` (whose RPATH in the wheels points elsewhere)."""
        wheel_libs = sorted(self._site(self.root / "venv").glob("ros_*.libs"))
        return [*(p / "lib" for p in self.prefixes), *wheel_libs]

    def variables(self, distro: str) -> dict[str, str]:
        """The environment variables a process needs (prepended to the current ``LD_LIBRARY_PATH`` and
        ``AMENT_PREFIX_PATH``)."""
        def joined(dirs: list[Path], name: str) -> str:
            return ":".join([*map(str, dirs), *filter(None, os.environ.get(name, "").split(":"))])

        return {ENV_VAR: str(self.root), "ROS_DISTRO": distro, "LD_LIBRARY_PATH": joined(self.lib_dirs,
                "LD_LIBRARY_PATH"), "AMENT_PREFIX_PATH": joined(self.prefixes, "AMENT_PREFIX_PATH")}

    def shell_lines(self, distro: str) -> list[str]:
        """``export`` lines (POSIX shell) for ``eval "$(ur3hanoi ros2-env)"``; existing paths are kept, after."""
        def path(dirs: list[Path], name: str) -> str:
            return f"export {name}={shlex.quote(':'.join(map(str, dirs)))}${{{name}:+:${name}}}"

        return [f"export {ENV_VAR}={shlex.quote(str(self.root))}", f"export ROS_DISTRO={distro}",
                path(self.lib_dirs, "LD_LIBRARY_PATH"), path(self.prefixes, "AMENT_PREFIX_PATH")]


def _use_env(root: Path) -> None:
    """Append the environment's Python folders to ``sys.path``, after checking it fits this process."""
    env = RclpyEnv.load(root)
    if env.python != _this_python():
        raise RclpyUnavailableError(f"{ENV_VAR}={root} was built for Python {env.python}, this is Python "
                                    f"{_this_python()}: run eval \"$(ur3hanoi ros2-env)\" with this Python")
    search = os.environ.get("LD_LIBRARY_PATH", "").split(":")
    if str(env.root / "venv" / "lib") not in search:
        raise RclpyUnavailableError(f"{ENV_VAR} is set but LD_LIBRARY_PATH lacks its libraries: set both with "
                                    "eval \"$(ur3hanoi ros2-env)\"")
    for d in map(str, env.site_dirs):
        if d not in sys.path:
            sys.path.append(d)


def import_rclpy() -> ModuleType:
    """The ``rclpy`` module, from the ``ros2-env`` environment :data:`ENV_VAR` names or from ``sys.path``.

    Raises:
        RclpyUnavailableError: neither gives a working rclpy; one line with both ways to get it.
    """
    root = os.environ.get(ENV_VAR)
    if root:
        _use_env(Path(root))
    try:
        return importlib.import_module("rclpy")
    except ModuleNotFoundError as exc:
        if exc.name != "rclpy":
            raise RclpyUnavailableError(f"rclpy does not load in Python {_this_python()}: module {exc.name} is "
                                        f"missing: {HINT}") from None
        raise RclpyUnavailableError(f"rclpy is not importable in Python {_this_python()} ({sys.executable}): "
                                    f"{HINT}") from None
    except ImportError as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise RclpyUnavailableError(f"rclpy does not load in Python {_this_python()} ({first}): {HINT}") from None


def import_interfaces(*modules: str) -> list[ModuleType]:
    """The message modules (``control_msgs.action``, ``ur_msgs.srv``, ...) after :func:`import_rclpy`.

    Raises:
        RclpyUnavailableError: one is missing; the line names its package and both ways to get it.
    """
    out = []
    for name in modules:
        try:
            out.append(importlib.import_module(name))
        except ImportError as exc:
            package = name.split(".")[0]
            raise RclpyUnavailableError(f"{package} is not importable ({str(exc).splitlines()[0]}): with a ROS 2 "
                                        f"installation install ros-$ROS_DISTRO-{package.replace('_', '-')}; "
                                        f"else {HINT}") from None
    return out
