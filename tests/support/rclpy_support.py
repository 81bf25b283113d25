"""A real rclpy as a test peer: the environments ``ur3hanoi ros2-env`` builds (ROS 2 Jazzy wheels, Fast-RTPS 2.14;
Kilted wheels, Fast DDS 3.2), never the project's own virtual environment.

:func:`build_env` builds one with :func:`ur3hanoi.interface.ros2.rclpy_build.ensure_env` (the one home of the package
pins and the message build) for the interpreter running the tests, adding the course's ``ur3e_mrc_msgs`` (the student
programs' messages) to the UR driver's ``control_msgs`` and ``ur_msgs``. It lives in the user's real cache
(``UR3HANOI_RCLPY_CACHE``, set by tests/conftest.py: the suite's own cache is a temporary folder), so a machine builds
each distribution once, for the tests and for ``ur3hanoi ros2-env`` alike. The same environment serves a peer (its
own interpreter, as a ROS 2 user's program runs) and ur3hanoi's rclpy code (the project's interpreter, with the lines
``ros2-env`` prints).
"""

from __future__ import annotations

import os
import shlex
import sys
from dataclasses import dataclass
from pathlib import Path

from ur3hanoi.interface.ros2.msgs import MSG_TEXT
from ur3hanoi.interface.ros2.rclpy_build import WHEELS, MsgPackage, ensure_env

DISTROS: dict[str, str] = {"jazzy": "jazzy", "kilted": "kilted"}
"""The distributions the peers run (one environment each) -> the ``--ros-distro`` of ur3hanoi's side."""

COURSE_MSGS = MsgPackage("ur3e_mrc_msgs", {f"msg/{name.rsplit('/', 1)[1]}.msg": text
                                           for name, text in MSG_TEXT.items()}, ())


def cache_base() -> Path:
    """The user's real cache folder of ur3hanoi (where ``ros2-env`` builds too)."""
    base = Path(os.environ.get("UR3HANOI_RCLPY_CACHE") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "ur3hanoi"


@dataclass(frozen=True)
class PeerEnv:
    """One built environment: a peer's interpreter and variables, and those of ur3hanoi's own rclpy process."""

    distro: str
    python: str
    peer: dict[str, str]
    station: dict[str, str]

    def peer_command(self, *args: str) -> str:
        """The shell command running a script with the peer's interpreter and variables (that process only)."""
        assigns = [f"{k}={shlex.quote(v)}" for k, v in self.peer.items()]
        return " ".join(["env", *assigns, shlex.quote(self.python), *map(shlex.quote, args)])

    def station_prefix(self) -> str:
        """``env NAME=value ...``: what ``eval "$(ur3hanoi ros2-env)"`` sets, for one ur3hanoi command."""
        return " ".join(["env", *(f"{k}={shlex.quote(v)}" for k, v in self.station.items())])


def build_env(distro: str) -> PeerEnv:
    """Build (once) the ``distro`` environment (minutes on a fresh machine, milliseconds after)."""
    env = ensure_env(cache_base(), WHEELS[distro], sys.executable, extra=(COURSE_MSGS,))
    station = env.variables(distro)
    msgs = [d for d in env.site_dirs if d.parent.parent.parent.parent.name == "msgs"]
    peer = {"PYTHONPATH": ":".join(map(str, msgs)), "LD_LIBRARY_PATH": station["LD_LIBRARY_PATH"],
            "AMENT_PREFIX_PATH": station["AMENT_PREFIX_PATH"], "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp",
            "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    return PeerEnv(distro, str(env.python_exe), peer, station)
