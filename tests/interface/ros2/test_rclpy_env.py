"""ur3hanoi.interface.ros2.rclpy_env without rclpy: the one-line errors when rclpy is missing or the environment does
not fit, the lines ``ros2-env`` prints as a shell sees them, the folders appended after the project's own. The real
import runs in tests/interface/ros2/test_rclpy_build.py (marker rclpy)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from ur3hanoi.interface.ros2 import distros, rclpy_env
from ur3hanoi.interface.ros2.errors import RclpyUnavailableError
from ur3hanoi.interface.ros2.rclpy_env import ENV_VAR, RclpyEnv, write_manifest

PY = f"{sys.version_info[0]}.{sys.version_info[1]}"


def _fake_env(root: Path, python: str = PY) -> RclpyEnv:
    """A manifest and the folders it names (no rclpy inside)."""
    dirs = [root / "msgs" / "control_msgs", root / "msgs" / "ur_msgs", root / "venv"]
    for d in dirs:
        (d / "lib" / f"python{python}" / "site-packages").mkdir(parents=True)
    (root / "venv" / "lib" / f"python{python}" / "site-packages" / "ros_rcl.libs").mkdir()
    write_manifest(root, "jazzy", python, ["ros-jazzy-rclpy==7.1.6"], {"control_msgs": "k1", "ur_msgs": "k2"})
    return RclpyEnv.load(root)


def test_without_rclpy_one_line_names_both_ways(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if "rclpy" not in p])
    with pytest.raises(RclpyUnavailableError) as e:
        rclpy_env.import_rclpy()
    text = str(e.value)
    assert "\n" not in text and f"Python {PY}" in text
    assert 'eval "$(ur3hanoi ros2-env)"' in text and "source a ROS 2 installation" in text


def test_an_incomplete_environment_is_named(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    with pytest.raises(RclpyUnavailableError, match=f"{tmp_path} is not a complete ros2-env environment"):
        rclpy_env.import_rclpy()


def test_an_environment_of_another_python_is_refused(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _fake_env(tmp_path, "3.9")
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    with pytest.raises(RclpyUnavailableError, match=f"built for Python 3.9, this is Python {PY}"):
        rclpy_env.import_rclpy()


def test_the_library_path_must_come_with_it(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _fake_env(tmp_path)
    monkeypatch.setenv(ENV_VAR, str(tmp_path))
    monkeypatch.setenv("LD_LIBRARY_PATH", "/usr/lib")
    with pytest.raises(RclpyUnavailableError, match="LD_LIBRARY_PATH lacks its libraries"):
        rclpy_env.import_rclpy()


def test_site_folders_are_appended_after_the_projects_own(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    env = _fake_env(tmp_path)
    for k, v in env.variables("jazzy").items():
        monkeypatch.setenv(k, v)
    before = list(sys.path)
    monkeypatch.setattr(sys, "path", before.copy())
    with pytest.raises(RclpyUnavailableError, match="rclpy is not importable"):
        rclpy_env.import_rclpy()  # the fake environment has no rclpy
    assert sys.path[:len(before)] == before
    assert sys.path[len(before):] == [str(d) for d in env.site_dirs]
    assert str(env.site_dirs[-1]).endswith(f"venv/lib/python{PY}/site-packages")


def test_shell_lines_set_what_variables_say(tmp_path: Path) -> None:
    """The eval'd lines give a shell the same values as :meth:`RclpyEnv.variables` (a space in the path, an old
    LD_LIBRARY_PATH kept after the new folders)."""
    env = _fake_env(tmp_path / "with space")
    script = "\n".join([*env.shell_lines("humble"), f'echo "${ENV_VAR}"', 'echo "$ROS_DISTRO"',
                        'echo "$LD_LIBRARY_PATH"', 'echo "$AMENT_PREFIX_PATH"'])
    out = subprocess.run(["sh", "-c", script], capture_output=True, text=True, check=True,
                         env={"LD_LIBRARY_PATH": "/old/lib", "PATH": "/usr/bin:/bin"}).stdout.splitlines()
    root, distro, libs, prefixes = out
    assert root == str(env.root) and distro == "humble"
    assert libs.split(":") == [*map(str, env.lib_dirs), "/old/lib"]
    assert prefixes.split(":") == [str(p) for p in env.prefixes]
    assert str(tmp_path / "with space" / "venv" / "lib" / f"python{PY}" / "site-packages" / "ros_rcl.libs") in libs


@pytest.mark.parametrize(("value", "expected"), [("kilted", "kilted"), ("humble", "humble"), ("noetic", "jazzy"),
                                                 ("", "jazzy")])
def test_default_distro_follows_ros_distro(value: str, expected: str, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("ROS_DISTRO", value)
    assert distros.default_distro() == expected
