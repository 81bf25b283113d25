"""Find ROS 1 (Debian's packages) from the project's Python, and the environment a lab program needs.

Debian 12 ships ROS 1 as ordinary packages: ``ros-core`` (``roscore``) and the pure-Python ``python3-rospy``,
``python3-genpy`` and ``python3-std-msgs`` in ``/usr/lib/python3/dist-packages``. The project's virtual environment
imports them once that folder is on ``sys.path``; it is **appended** (never prepended) so the environment's own
numpy and PyYAML keep precedence over Debian's copies.

A lab program (``lab2_exec.py``) needs ``rospy`` and the course's ``ur3_driver.msg`` package.
:func:`ur3hanoi.interface.ros1.msgs.write_client_env` writes a folder with the generated ``ur3_driver`` package
and a ``sitecustomize.py`` that appends Debian's folder, so that ``PYTHONPATH=<folder>`` is all a Python 3 (the
venv's or Debian's own) needs; :func:`env_lines` are the shell lines ``ur3hanoi ros-env`` prints.
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import shlex
import shutil
import sys
from pathlib import Path
from types import ModuleType

from ur3hanoi.interface.ros1.errors import RosUnavailableError

ROS_PYTHON_DIR = Path("/usr/lib/python3/dist-packages")
"""Where Debian installs rospy, genpy, genmsg and std_msgs."""

DEBIAN_PACKAGES: tuple[str, ...] = ("ros-core", "python3-rospy", "python3-genpy", "python3-std-msgs")
"""The Debian packages ur3hanoi's ROS commands need (``tools/ensure-system-deps.sh`` installs them)."""
DRIVER_PACKAGES: tuple[str, ...] = ("python3-actionlib", "python3-actionlib-msgs", "python3-trajectory-msgs",
                                    "python3-sensor-msgs")
"""The Debian packages the official UR driver's interface needs besides (``--driver ur``)."""

_ROS_MODULES: tuple[str, ...] = ("rospy", "genpy", "genmsg", "std_msgs")
_DRIVER_MODULES: tuple[str, ...] = ("actionlib", "actionlib_msgs", "trajectory_msgs", "sensor_msgs")

_INSTALL_HINT = (f"install Debian's packages {' '.join(DEBIAN_PACKAGES)} (as root: bash tools/ensure-system-deps.sh, "
                 f"or apt-get install -y {' '.join(DEBIAN_PACKAGES)})")


def ensure_ros_python() -> None:
    """Make rospy, genpy, genmsg and std_msgs importable, appending :data:`ROS_PYTHON_DIR` to ``sys.path``.

    Raises:
        RosUnavailableError: a module is still not importable; the message names the Debian packages.
    """
    folder = str(ROS_PYTHON_DIR)
    if ROS_PYTHON_DIR.is_dir() and folder not in sys.path:
        sys.path.append(folder)
    missing = [m for m in _ROS_MODULES if importlib.util.find_spec(m) is None]
    if missing:
        raise RosUnavailableError(f"ROS 1 Python modules {', '.join(missing)} are not importable (searched sys.path "
                                  f"and {folder}): {_INSTALL_HINT}")


def ensure_driver_python() -> None:
    """:func:`ensure_ros_python`, and actionlib, actionlib_msgs, trajectory_msgs and sensor_msgs (``--driver ur``).

    Raises:
        RosUnavailableError: a module is not importable; the message names the Debian packages.
    """
    ensure_ros_python()
    missing = [m for m in _DRIVER_MODULES if importlib.util.find_spec(m) is None]
    if missing:
        raise RosUnavailableError(f"ROS 1 Python modules {', '.join(missing)} (for the UR driver's interface) are not "
                                  f"importable: install Debian's packages {' '.join(DRIVER_PACKAGES)} (as root: bash "
                                  f"tools/ensure-system-deps.sh, or apt-get install -y {' '.join(DRIVER_PACKAGES)})")


def import_rospy() -> ModuleType:
    """The ``rospy`` module (after :func:`ensure_ros_python`)."""
    ensure_ros_python()
    return importlib.import_module("rospy")


def import_std_msgs() -> ModuleType:
    """The ``std_msgs.msg`` module (``Int32`` for the station's spawn and fault topics)."""
    ensure_ros_python()
    return importlib.import_module("std_msgs.msg")


def roscore_executable(name: str = "roscore") -> str:
    """Path of ``roscore`` (or another program of package ``ros-core``, e.g. ``rosmaster``).

    Raises:
        RosUnavailableError: not on PATH (package ``ros-core`` missing).
    """
    path = shutil.which(name)
    if path is None:
        raise RosUnavailableError(f"{name} is not on PATH: {_INSTALL_HINT}")
    return path


def default_cache_dir() -> Path:
    """``$XDG_CACHE_HOME/ur3hanoi/ros`` (``~/.cache/ur3hanoi/ros`` when XDG_CACHE_HOME is unset)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ur3hanoi" / "ros"


SITECUSTOMIZE_MARK = "Written by `ur3hanoi ros-env`"
"""How a ``sitecustomize.py`` written by ``ros-env`` (any version, any folder) is recognised: never chained to."""

SITECUSTOMIZE = f'''"""{SITECUSTOMIZE_MARK}: lets any Python 3 import Debian's ROS 1 packages (rospy,
genpy) and the course's ur3_driver messages beside this file. Debian's folder is APPENDED to sys.path, so a virtual
environment's own packages (numpy, PyYAML) keep precedence. Then runs the next sitecustomize on the path (e.g.
Debian's), which this file would otherwise hide: once per process, and never another one written by ros-env
(`ros-env` applied twice, or with two folders, must not chain these files into each other forever)."""
import importlib.util as _util
import os as _os
import sys as _sys

_ROS = {str(ROS_PYTHON_DIR)!r}
_MARK = {SITECUSTOMIZE_MARK.encode()!r}
if _os.path.isdir(_ROS) and _ROS not in _sys.path:
    _sys.path.append(_ROS)


def _chain():
    if getattr(_sys, "_ur3hanoi_ros_env_chained", False):
        return
    _sys._ur3hanoi_ros_env_chained = True
    for entry in list(_sys.path):
        path = _os.path.join(_os.path.abspath(entry or "."), "sitecustomize.py")
        try:
            with open(path, "rb") as f:
                head = f.read(512)
        except OSError:
            continue
        if _MARK in head:
            continue
        spec = _util.spec_from_file_location("_ur3hanoi_next_sitecustomize", path)
        if spec is not None and spec.loader is not None:
            spec.loader.exec_module(_util.module_from_spec(spec))
        return


_chain()
'''


def env_lines(folder: Path, master_uri: str) -> list[str]:
    """The ``export`` lines that let a lab program in this shell talk to ``master_uri`` with the messages in
    ``folder`` (POSIX shell syntax, for ``eval "$(ur3hanoi ros-env)"``)."""
    quoted = shlex.quote(str(folder))
    return [
        f"export ROS_MASTER_URI={shlex.quote(master_uri)}",
        f"export PYTHONPATH={quoted}${{PYTHONPATH:+:$PYTHONPATH}}",
    ]
