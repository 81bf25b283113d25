"""The ROS subcommands' argument handling: one-line errors, exit code 2, before any motion (no ROS master used)."""

from __future__ import annotations

import pytest

from tests.support.ros_support import free_port
from ur3hanoi.cli import main


def error_line(capsys) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.mark.parametrize(("argv", "message"), [
    (["ros-solve", "--start", "1"], "--start and --end are required when stdin is not a terminal (towers 1..3)"),
    (["ros-solve", "--start", "1", "--end", "3", "--key", "real_pos"], "--key is only used with --table"),
    (["ros-solve", "--start", "2", "--end", "2"], "start and end tower are both 2"),
    (["ros-solve", "--start", "1", "--end", "4"], "--end 4 is invalid: expected a tower 1..3 (lab_sim has 3 towers)"),
    (["ros-solve", "--start", "1", "--end", "3", "--blocks", "4"], "4 blocks is invalid: expected 1..3"),
    (["ros-station", "--start", "4"], "start tower 4 is invalid: expected 1..3"),
    (["ros-station", "--remove-block", "5"], "removed block height 5 is invalid: expected 1..3"),
    (["ros-station", "--master", "localhost:11311"], "ROS master URI 'localhost:11311' is invalid"),
    (["ros-station", "--master", "http://robot-pc.example:11311"],
     "the ROS master http://robot-pc.example:11311 is on another machine, which cannot reach a station listening on "
     "loopback only: give --host ADDR"),
    (["ros-station", "--host", "lab-pc"], "host 'lab-pc' is invalid: expected this machine's IP address"),
    (["ros-env", "--master", "http://localhost"], "ROS master URI 'http://localhost' is invalid"),
    (["ros-station", "--program-stop-at", "3"], "--program-stop-at needs --driver ur"),
    (["ros-station", "--driver", "ur", "--program-stop-at", "5", "--program-resume-at", "2"],
     "--program-resume-at 2 needs an earlier --program-stop-at (got 5)"),
    (["ros2-station", "--driver", "ur", "--program-resume-at", "3"],
     "--program-resume-at 3 needs an earlier --program-stop-at (got none)"),
])
def test_bad_arguments_exit_2_with_one_line(argv, message, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin.isatty", lambda: False)
    assert main(argv) == 2
    line = error_line(capsys)
    assert line.startswith("ur3hanoi: error: ") and message in line


@pytest.mark.parametrize(("argv", "message"), [
    (["ros-station", "--rate", "30"], "argument --rate: '30' is invalid: expected a control and publishing rate [Hz] "
                                      "in [50, 500]"),
    (["ros-solve", "--v", "0"], "argument --v: '0' is invalid"),
    (["ros-solve", "--grasp-timeout", "nan"], "argument --grasp-timeout: 'nan' is invalid"),
])
def test_bad_option_values_exit_2_with_one_line(argv, message, capsys):
    assert main(argv) == 2
    line = error_line(capsys)
    assert line.startswith("ur3hanoi: error: ") and message in line and f"ur3hanoi {argv[0]} --help" in line, line


def test_ros_solve_without_a_master_exits_2(capsys):
    uri = f"http://127.0.0.1:{free_port()}"
    assert main(["ros-solve", "--start", "1", "--end", "3", "--master", uri]) == 2
    assert f"ur3hanoi: error: no ROS master answers at {uri}: start `ur3hanoi ros-station`" in error_line(capsys)


@pytest.mark.parametrize(("command", "station"), [("ros-solve", "lab_sim"), ("ros2-solve", "ur3e_sim")])
@pytest.mark.parametrize("option", ["--start", "--end"])
def test_tower_ranges_are_the_stations(command, station, option, capsys, monkeypatch):
    """`--start 0` names the station's 1..3, not the option's widest 1..10, and nothing is sent anywhere."""
    monkeypatch.setattr("sys.stdin.isatty", lambda: False)
    other = "--end" if option == "--start" else "--start"
    assert main([command, option, "0", other, "2"]) == 2
    expected = f"ur3hanoi: error: {option} 0 is invalid: expected a tower 1..3 ({station} has 3 towers)"
    assert error_line(capsys) == expected


@pytest.mark.parametrize("command", ["ros-station", "ros2-station"])
@pytest.mark.parametrize(("option", "target", "expected"), [
    ("--video", "{tmp}", "is a directory"),
    ("--video", "{tmp}/run.avi2", "extension"),
    ("--frames", "{tmp}/missing/frames", "missing does not exist"),
    ("--report", "/proc/report.json", "the directory /proc does not accept new files"),
])
def test_station_outputs_are_refused_before_the_station_starts(command, option, target, expected, tmp_path,
                                                              monkeypatch, capsys):
    """Both stations check --video, --frames and --report the same way (ur3hanoi.io.atomic), in one line, before
    anything runs (no master, no DDS participant, no rendering process) and without creating a file."""
    from ur3hanoi.interface.ros1.server import RosServer
    from ur3hanoi.interface.ros2.server import Ros2Server

    started: list[str] = []
    for cls in (RosServer, Ros2Server):
        monkeypatch.setattr(cls, "run", lambda self: started.append(type(self).__name__) or {})
    target = target.format(tmp=tmp_path)
    assert main([command, "--duration", "0.5", option, target]) == 2
    line = error_line(capsys)
    assert line.startswith("ur3hanoi: error: cannot write ") and target in line and expected in line, line
    assert started == []
    assert sorted(p.name for p in tmp_path.iterdir()) == []
