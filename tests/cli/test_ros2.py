"""The ROS 2 subcommands' argument handling and the UR driver interface without rclpy: one line, exit 2, before any
world is loaded or plan made, naming both ways to get rclpy; the course-topic commands need none."""

from __future__ import annotations

import sys

import pytest

from ur3hanoi.cli import main
from ur3hanoi.interface.ros2.rclpy_env import ENV_VAR


def error_line(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.fixture
def no_rclpy(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(ENV_VAR, raising=False)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if "rclpy" not in p and "/opt/ros" not in p])


@pytest.mark.parametrize("argv", [["ros2-station", "--driver", "ur"],
                                  ["ros2-solve", "--driver", "ur", "--start", "1", "--end", "3"]])
def test_the_ur_driver_interface_without_rclpy_is_one_line(argv: list[str], no_rclpy: None,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    line = error_line(capsys)
    assert line.startswith("ur3hanoi: error: rclpy is not importable in Python")
    assert 'eval "$(ur3hanoi ros2-env)"' in line and "source a ROS 2 installation" in line
    assert "rclpy" not in sys.modules


@pytest.mark.parametrize(("argv", "message"), [
    (["ros2-station", "--driver", "ur", "--ros-distro", "noetic"], "argument --ros-distro: invalid choice: 'noetic'"),
    (["ros2-station", "--driver", "ur", "--speed-scaling", "0"], "argument --speed-scaling: '0' is invalid"),
    (["ros2-solve", "--driver", "ur", "--start", "1", "--end", "3", "--wait", "0.1"], "argument --wait: '0.1' is "
     "invalid"),
    (["ros2-env", "--distro", "iron"], "argument --distro: invalid choice: 'iron'"),
])
def test_bad_driver_options_exit_2_with_one_line(argv: list[str], message: str,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    line = error_line(capsys)
    assert line.startswith("ur3hanoi: error: ") and message in line
