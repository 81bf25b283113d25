"""The `ur3hanoi` command: exit codes, one-line errors, option ranges, refused outputs, no traceback ever."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from tests.conftest import LAB_REAL, LAB_SIM, REPO
from tests.support.ros_support import free_port, requires_ros, ros_env, run, ur3hanoi_cmd
from ur3hanoi.cli import main, progress
from ur3hanoi.cli.exit_codes import EXIT_CODES, exit_code_for
from ur3hanoi.cli.options import DWELL, RATE, SEED, SPEED, option
from ur3hanoi.errors import PlanError, SuctionFaultError, Ur3HanoiError

LAB_TABLE = REPO / "tables/lab2_data.yaml"


def _bad_calibration(tmp_path: Path, **grid: object) -> Path:
    raw = yaml.safe_load(LAB_REAL.read_text())
    raw["grid"].update(grid)
    path = tmp_path / "bad_station.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


def _one_error_line(err: str) -> str:
    assert err.count("\n") == 1 and err.endswith("\n"), err
    assert "Traceback" not in err
    return err


# ------------------------------------------------------------------------------------------------- tables


def test_tables_writes_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(LAB_SIM), "--key", "sim_pos", "-o", str(out), "--solver", "placo"]) == 0
    assert "wrote sim_pos" in capsys.readouterr().out
    assert "placo IK" in out.read_text()


def test_tables_writes_into_a_students_own_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # Unknown keys, junk in the key being replaced, a malformed key not touched: all the student's, all kept.
    out = tmp_path / "lab2_data.yaml"
    mine = "# group 7\nhome_pos: [1, 2]\nextra_notes: {ok: yes}\nreal_pos: [[1]]   # not touched\n"
    out.write_text(mine + "sim_pos: old\n")
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(out)]) == 0, capsys.readouterr().err
    text = out.read_text()
    assert text.startswith(mine) and "sim_pos: old" not in text
    assert main(["check-table", str(out), "--key", "sim_pos", "--calibration", "lab_sim"]) == 0
    # Only a file whose top level is not a mapping is refused: one line, exit 2, the file untouched.
    out.write_text("- home_pos\n- sim_pos\n")
    capsys.readouterr()
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(out)]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert "lab2_data.yaml: the top level is a list, not a mapping of keys" in err
    assert out.read_text() == "- home_pos\n- sim_pos\n"


def test_unreachable_grid_exits_2_with_one_line_and_writes_nothing(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    cal = _bad_calibration(tmp_path, tower_origins=[[0.25, -0.20, 0.0288], [0.25, -0.09, 0.0288],
                                                    [0.95, 0.04, 0.0288]])
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(out)]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert "tower 3 height 1 on" in err and "unreachable" in err and "target xyz" in err and "residual" in err
    assert not out.exists()


def test_unreachable_grid_keeps_existing_file(tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(LAB_SIM), "--key", "sim_pos", "-o", str(out)]) == 0
    before = out.read_bytes()
    cal = _bad_calibration(tmp_path, approach=0.45)
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(out)]) == 2
    assert out.read_bytes() == before


def test_invalid_calibration_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cal = _bad_calibration(tmp_path, heights=0)
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(tmp_path / "o.yaml")]) == 2
    err = capsys.readouterr().err
    assert "bad_station.yaml: field 'grid.heights' = 0 is invalid: expected an integer in [1, 20]" in err


def test_typo_in_calibration_is_refused_by_tables(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cal = tmp_path / "typo.yaml"
    cal.write_text(LAB_SIM.read_text().replace("base_rpy_deg: [0, 0, 0]", "base_rpy: [0, 0, 90]"))
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(cal), "--key", "sim_pos", "-o", str(out)]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert "field 'robot.base_rpy' is unknown: did you mean 'robot.base_rpy_deg'?" in err
    assert not out.exists()


def test_missing_calibration_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tables", str(tmp_path / "nope.yaml"), "--key", "sim_pos", "-o", str(tmp_path / "o.yaml")]) == 2
    assert "nope.yaml" in capsys.readouterr().err


def test_bad_key_is_a_one_line_usage_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tables", str(LAB_SIM), "--key", "gazebo", "-o", str(tmp_path / "o.yaml")]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert err.startswith("ur3hanoi: error: argument --key: invalid choice: 'gazebo'")
    assert err.rstrip().endswith("(see ur3hanoi tables --help)")


def test_help_and_version_return_0(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.startswith("ur3hanoi ")
    assert main(["tables", "--help"]) == 0
    assert "a symlink is written through to its target" in " ".join(capsys.readouterr().out.split())


# ------------------------------------------------------------------------------------------------ check-table


def test_check_table_ok_and_fail(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["check-table", str(LAB_TABLE), "--key", "real_pos", "--calibration", str(LAB_REAL)]) == 0
    assert "18/18 entries within 1.0 mm / 0.5 deg" in capsys.readouterr().out
    # The same joints judged against another station's grid are far off: exit 1.
    assert main(["check-table", str(LAB_TABLE), "--key", "real_pos", "--calibration", str(LAB_SIM)]) == 1
    assert "0/18 entries" in capsys.readouterr().out


def test_check_table_on_hand_recorded_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = yaml.safe_load(LAB_TABLE.read_text())
    q = data["real_pos"]
    q[0][1][1][0] += 0.002  # a 2 mrad pan error on one recorded entry
    hand = tmp_path / "hand.yaml"
    hand.write_text(yaml.safe_dump({"real_pos": q}, default_flow_style=True))
    assert main(["check-table", str(hand), "--key", "real_pos", "--calibration", str(LAB_REAL)]) == 0
    out = capsys.readouterr().out
    assert "17/18" not in out  # 2 mrad at 0.3 m is 0.6 mm: within 1 mm
    assert main(["check-table", str(hand), "--key", "real_pos", "--calibration", str(LAB_REAL),
                 "--tol-mm", "0.1"]) == 1
    assert "17/18 entries within 0.1 mm" in capsys.readouterr().out


def test_check_table_missing_key_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    only_sim = tmp_path / "sim.yaml"
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(only_sim)]) == 0
    capsys.readouterr()
    assert main(["check-table", str(only_sim), "--key", "real_pos", "--calibration", str(LAB_REAL)]) == 2
    assert "key 'real_pos' not found (table keys present: sim_pos)" in _one_error_line(capsys.readouterr().err)


# ---------------------------------------------------------------------------------------------------- options

SPEED_RANGE = "a fraction of the joint speed, acceleration and jerk limits in [0.01, 1]"
BAD_OPTIONS = [
    (["plan", "--start", "1", "--end", "3", "--rate", "1e-9"], "--rate", "a sample rate [Hz] in [1, 10000]"),
    (["plan", "--start", "1", "--end", "3", "--rate", "1e9"], "--rate", "a sample rate [Hz] in [1, 10000]"),
    (["plan", "--start", "1", "--end", "3", "--rate", "nan"], "--rate", "a sample rate [Hz] in [1, 10000]"),
    (["plan", "--start", "1", "--end", "3", "--speed", "1e-12"], "--speed", SPEED_RANGE),
    (["plan", "--start", "1", "--end", "3", "--speed", "1.5"], "--speed", SPEED_RANGE),
    (["plan", "--start", "1", "--end", "3", "--dwell", "1e300"], "--dwell", "a dwell time [s] in [0, 10]"),
    (["plan", "--start", "1", "--end", "3", "--dwell", "-0.1"], "--dwell", "a dwell time [s] in [0, 10]"),
    (["plan", "--start", "1", "--end", "3", "--blocks", "11"], "--blocks", "a number of blocks in [1, 10]"),
    (["plan", "--start", "1", "--end", "3", "--blocks", "2.5"], "--blocks", "a number of blocks in [1, 10]"),
    (["solve", "--start", "1", "--end", "3", "--seed", "-1"], "--seed", "a seed in [0, 4294967295]"),
    (["solve", "--start", "1", "--end", "3", "--seed", str(2**32)], "--seed", "a seed in [0, 4294967295]"),
    (["solve", "--start", "1", "--end", "3", "--seed", "9" * 5000], "--seed", "a seed in [0, 4294967295]"),
    (["solve", "--start", "1", "--end", "3", "--speed", "0"], "--speed", SPEED_RANGE),
    (["solve", "--start", "1", "--end", "3", "--drop-during-move", "1e3"], "--drop-during-move", "a move number"),
    (["check-table", str(LAB_TABLE), "--key", "real_pos", "--calibration", "lab_real", "--tol-mm", "0"],
     "--tol-mm", "a position tolerance [mm] in (0, 1000]"),
    (["check-table", str(LAB_TABLE), "--key", "real_pos", "--calibration", "lab_real", "--tol-deg", "inf"],
     "--tol-deg", "an orientation tolerance [deg] in (0, 180]"),
]


@pytest.mark.parametrize(("argv", "message"), [
    (["plan", "--start", "0", "--end", "3"], "--start 0 is invalid: expected a tower 1..3 (lab_sim has 3 towers)"),
    (["solve", "--start", "1", "--end", "4"], "--end 4 is invalid: expected a tower 1..3 (lab_sim has 3 towers)"),
    (["solve", "--start", "1", "--end", "3", "--blocks", "2", "--remove-block", "3"],
     "--remove-block 3 is invalid: expected a height 1..2 (2 blocks are spawned)"),
    (["solve", "--start", "1", "--end", "3", "--blocks", "2", "--drop-during-move", "4"],
     "--drop-during-move 4 is invalid: expected a move 1..3 (2 blocks take 3 moves)"),
])
def test_tower_height_and_move_ranges_are_the_stations(argv: list[str], message: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    assert _one_error_line(capsys.readouterr().err) == f"ur3hanoi: error: {message}\n"


@pytest.mark.parametrize(("argv", "flag", "expected"), BAD_OPTIONS, ids=[" ".join(a[-2:])[:30] for a, _, _ in
                                                                            BAD_OPTIONS])
def test_every_numeric_option_is_range_checked(argv: list[str], flag: str, expected: str,
                                               capsys: pytest.CaptureFixture[str]) -> None:
    assert main(argv) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert f"error: argument {flag}: " in err and f"is invalid: expected {expected}" in err
    assert len(err) < 300


@pytest.mark.parametrize(("spec", "ok", "bad"), [(SPEED, ["0.01", "1"], ["0.0099", "1.0001"]),
                                                  (RATE, ["1", "10000"], ["0.999", "10000.1"]),
                                                  (DWELL, ["0", "10"], ["-1e-9", "10.001"]),
                                                  (SEED, ["0", str(2**32 - 1)], [str(2**32), "1.0"])])
def test_option_range_boundaries(spec: object, ok: list[str], bad: list[str]) -> None:
    import argparse

    parse = option(spec)  # type: ignore[arg-type]
    for text in ok:
        assert parse(text) == float(text)
    for text in bad:
        with pytest.raises(argparse.ArgumentTypeError):
            parse(text)


def test_plan_too_large_is_refused_before_planning(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["plan", "--start", "1", "--end", "3", "--calibration", "lab_real", "--rate", "10000", "--speed", "0.01"]
    assert main(argv) == 2
    assert "more than 5000000: use fewer blocks" in _one_error_line(capsys.readouterr().err)


def test_blocks_beyond_the_grid_is_a_puzzle_error(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["plan", "--start", "1", "--end", "3", "--blocks", "4"]) == 2
    assert "4 blocks is invalid: expected 1..3" in _one_error_line(capsys.readouterr().err)


# ---------------------------------------------------------------------------------------------------- outputs


def test_output_that_is_the_input_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cal = tmp_path / "X.yaml"
    shutil.copy(LAB_REAL, cal)
    before = cal.read_bytes()
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(cal)]) == 2
    assert "it is also an input of this command" in _one_error_line(capsys.readouterr().err)
    assert cal.read_bytes() == before
    link = tmp_path / "link.yaml"
    link.symlink_to(cal)  # the same file under another name
    assert main(["calibrate", "--from-table", str(LAB_TABLE), "--key", "real_pos", "--base", str(cal),
                 "-o", str(link)]) == 2
    assert cal.read_bytes() == before
    assert main(["plan", "--start", "1", "--end", "3", "--calibration", str(cal), "--csv", str(cal)]) == 2
    assert cal.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["X.yaml", "link.yaml"]


@pytest.mark.parametrize("kind", ["directory", "fifo", "device", "missing-dir", "empty"])
def test_unwritable_outputs_are_refused_in_one_line(kind: str, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    out = {"directory": str(tmp_path), "fifo": str(tmp_path / "fifo"), "device": "/dev/null",
           "missing-dir": str(tmp_path / "no" / "t.yaml"), "empty": ""}[kind]
    if kind == "fifo":
        os.mkfifo(out)
    assert main(["tables", "lab_real", "--key", "real_pos", "-o", out]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert err.startswith("ur3hanoi: error: cannot write ")
    expected = {"directory": "it is a directory", "fifo": "it is a FIFO", "device": "it is a device",
                "missing-dir": "does not exist", "empty": "the path is empty"}[kind]
    assert expected in err
    assert [p.name for p in tmp_path.iterdir()] == (["fifo"] if kind == "fifo" else [])


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only directories")
def test_read_only_directory_is_refused(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o555)
    try:
        assert main(["tables", "lab_real", "--key", "real_pos", "-o", str(ro / "t.yaml")]) == 2
        assert "is not writable" in _one_error_line(capsys.readouterr().err)
    finally:
        ro.chmod(0o755)


def test_paths_with_control_characters_keep_the_header_a_comment(tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    cal = tmp_path / "cal\nsim_pos: 1\x1b[31m.yaml"
    shutil.copy(LAB_REAL, cal)
    out = tmp_path / "out\n.yaml"
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(out)]) == 0
    stdout = capsys.readouterr().out
    assert stdout.count("\n") == 1 and "\x1b" not in stdout
    assert main(["check-table", str(out), "--key", "real_pos", "--calibration", str(cal)]) == 0
    lines = out.read_text().splitlines()
    assert all(line.startswith(("#", "real_pos:", "- ", "  ")) for line in lines)
    station = tmp_path / "fitted\r\n\u2028.yaml"
    assert main(["calibrate", "--from-table", str(out), "--key", "real_pos", "--base", str(cal), "-o",
                 str(station)]) == 0
    header = [line for line in station.read_text().splitlines() if line.startswith("# ")]
    assert len(header) == 4 and "cal\\nsim_pos: 1\\x1b[31m.yaml" in header[2]
    assert main(["check-table", str(out), "--key", "real_pos", "--calibration", str(station)]) == 0


# ------------------------------------------------------------------------------------------- error mapping


def test_library_errors_map_to_exit_codes() -> None:
    from ur3hanoi.errors import DriverError, ProgramStoppedError

    assert exit_code_for(SuctionFaultError("halted")) == 3
    assert exit_code_for(ProgramStoppedError("the robot program stopped")) == 3
    assert exit_code_for(DriverError("x")) == 2
    assert exit_code_for(PlanError("x")) == 2
    assert exit_code_for(Ur3HanoiError("x")) == 2
    assert [code for _, code in EXIT_CODES] == [3, 3, 2]


def _raise(exc: BaseException) -> object:
    def boom(*args: object, **kwargs: object) -> object:
        raise exc

    return boom


def test_suction_fault_exits_3(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                               capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr("ur3hanoi.tables.ik_table.generate_table", _raise(SuctionFaultError("block 2 is not held")))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # nothing cached: tables generates its key
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(tmp_path / "t.yaml")]) == 3
    assert _one_error_line(capsys.readouterr().err) == "ur3hanoi: error: block 2 is not held\n"


def test_unexpected_exception_is_one_line_exit_70(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr("ur3hanoi.tables.ik_table.generate_table", _raise(ZeroDivisionError("float division\nby zero")))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # nothing cached: tables generates its key
    argv = ["tables", "lab_sim", "--key", "sim_pos", "-o", str(tmp_path / "t.yaml")]
    assert main(argv) == 70
    err = _one_error_line(capsys.readouterr().err)
    assert err == ("ur3hanoi: error: internal error in ur3hanoi tables: ZeroDivisionError: float division by zero "
                   "(a bug: rerun with --debug for the traceback)\n")
    with pytest.raises(ZeroDivisionError):
        main(["--debug", *argv])
    with pytest.raises(ZeroDivisionError):
        main([*argv, "--debug"])
    assert not (tmp_path / "t.yaml").exists()


def test_keyboard_interrupt_exits_130(monkeypatch: pytest.MonkeyPatch, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.setattr("ur3hanoi.tables.ik_table.generate_table", _raise(KeyboardInterrupt()))
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))  # nothing cached: tables generates its key
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(tmp_path / "t.yaml")]) == 130
    assert capsys.readouterr().err == "ur3hanoi tables: interrupted\n"


def test_fifo_input_does_not_hang(tmp_path: Path) -> None:
    fifo = tmp_path / "cal.yaml"
    os.mkfifo(fifo)
    res = subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "tables", str(fifo), "--key", "sim_pos", "-o",
                          str(tmp_path / "o.yaml")], capture_output=True, text=True, timeout=60)
    assert res.returncode == 2
    assert res.stderr == f"ur3hanoi: error: {fifo}: is a FIFO (named pipe), not a calibration file (expected a " \
                         "regular file)\n"


def test_console_script_entry_point() -> None:
    out = subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "--version"], capture_output=True, text=True,
                         check=True)
    assert out.stdout.startswith("ur3hanoi ")


def test_solve_render_outputs_are_checked_before_simulating(tmp_path: Path,
                                                             capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["solve", "--start", "1", "--end", "3", "--video", str(tmp_path)]) == 2
    assert "it is a directory" in _one_error_line(capsys.readouterr().err)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    assert main(["solve", "--start", "1", "--end", "3", "--frames", str(blocker / "frames")]) == 2
    assert f"cannot write {blocker / 'frames'}: " in _one_error_line(capsys.readouterr().err)
    assert _listing(tmp_path) == ["file"]


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


# ------------------------------------------------------------------- the table readers agree (issue 17)


class _FakeArm:
    """Stands in for ``ur3hanoi.interface.ros1.client.RosArm``: ros-solve's own table loading and moves, no ROS; suction
    holds a block whenever it is on. Every commanded pose must be six finite angles."""

    def __init__(self, config: object, master_uri: str | None = None, log: object = None) -> None:
        self.master_uri = "fake://"
        self.commands_sent = 0
        self.on = False

    def connect(self) -> None:
        pass

    def close(self) -> None:
        pass

    def move(self, q: object, watch: object = None) -> None:
        import numpy as np

        assert np.shape(q) == (6,) and np.all(np.isfinite(q)), q
        self.commands_sent += 1

    def suction(self, on: bool) -> None:
        self.on = on

    def held(self) -> bool:
        return self.on

    def wait_until(self, predicate: object, timeout_s: float) -> bool:
        return bool(predicate())  # type: ignore[operator]

    def feedback_text(self) -> str:
        return "DIGIN=1"


def _table_case(tmp_path: Path, case: str) -> Path:
    import numpy as np

    q = np.array(yaml.safe_load(LAB_TABLE.read_text())["sim_pos"], dtype=float).tolist()
    extra = ""
    if case == "unvisited-null-tower":  # one block from tower 1 to 3 never visits tower 2
        q[1] = None
    elif case == "visited-entry-missing":
        q[2][0][1] = None
    elif case == "other-keys-anything":
        extra = "home_pos: whatever\nreal_pos: old\nblock_xy_pos: [[1]]\n"
    path = tmp_path / f"{case}.yaml"
    path.write_text(extra + yaml.safe_dump({"sim_pos": q}))
    return path


@pytest.mark.parametrize(
    ("case", "accepted"),
    [("complete", True), ("unvisited-null-tower", True), ("visited-entry-missing", False),
     ("other-keys-anything", True)],
)
def test_solve_and_ros_solve_accept_and_refuse_the_same_tables(case: str, accepted: bool, tmp_path: Path,
                                                               monkeypatch: pytest.MonkeyPatch,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    import ur3hanoi.interface.ros1.client

    monkeypatch.setattr(ur3hanoi.interface.ros1.client, "RosArm", _FakeArm)
    path = _table_case(tmp_path, case)
    instance = ["--table", str(path), "--key", "sim_pos", "--start", "1", "--end", "3", "--blocks", "1"]
    codes = {}
    for command in ("solve", "ros-solve"):
        codes[command] = main([command, *instance])
        err = capsys.readouterr().err
        if not accepted:
            assert "1 table entry the solve needs is missing: tower 3 height 1 above (Q[2][0][1])" in \
                _one_error_line(err)
    assert codes == ({"solve": 0, "ros-solve": 0} if accepted else {"solve": 2, "ros-solve": 2})
    # check-table reads the same key the same way: every table here is readable (missing entries are listed).
    assert main(["check-table", str(path), "--key", "sim_pos", "--calibration", "lab_sim"]) == 0


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("{tower: 1, height: 1, q:", "{tower: 1, height: 1, pose: on, q:",
         "taught.yaml: field 'points[0].pose' = on (line 7) is ambiguous: YAML 1.1 reads on as the boolean true; for "
         "the text write it in quotes (pose: \"on\"); expected one of on, above"),
        ("{tower: 1, height: 3,", "{tower: 1, height: 010,", None),
        ("{tower: 3, height: 1, q: [157.43,", "{tower: 3, height: 1, q: [1:30,",
         "field 'points[2].q[0]' = 1:30 (line 9) is ambiguous: YAML 1.1 reads 1:30 as 90 (a base-60 number)"),
        ("{tower: 3, height: 1, q: [157.43,", "{tower: 3, height: 1, q: [1_57.43,",
         "field 'points[2].q[0]' = 1_57.43 (line 9) is ambiguous: YAML 1.1 reads 1_57.43 as 157.43 (its underscores "
         "dropped as digit separators); write the number itself (157.43) if that is what you mean"),
    ],
    ids=["pose-on", "octal-height", "sexagesimal-angle", "digit-separators"],
)
def test_yaml11_readings_in_a_taught_file_exit_2_quoting_the_source(old: str, new: str, message: str | None,
                                                                      tmp_path: Path,
                                                                      capsys: pytest.CaptureFixture[str]) -> None:
    taught = tmp_path / "taught.yaml"
    taught.write_text((REPO / "ur3hanoi/station/shipped/taught_example.yaml").read_text().replace(old, new, 1))
    out = tmp_path / "station.yaml"
    assert main(["calibrate", "--taught", str(taught), "--base", "lab_real", "-o", str(out)]) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert (message or "field 'points[3].height' = 010 (line 10) is ambiguous: YAML 1.1 reads 010 as the octal "
                       "number 8; write 10 or 8, whichever you mean, without the leading zero") in err
    assert not out.exists()


# ------------------------------------------------------------------------------ outputs: atomic and safe

OTHER_UID = 65534  # nobody


def _planted_link(tmp_path: Path, name: str) -> tuple[Path, Path]:
    """A victim file of the caller and a link to it planted by another user in a shared sticky directory."""
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o1777)
    link = shared / name
    link.symlink_to(victim)
    os.lchown(link, OTHER_UID, OTHER_UID)
    return link, victim


@pytest.mark.skipif(os.geteuid() != 0, reason="planting another user's link needs root (os.lchown)")
@pytest.mark.parametrize("command", ["plan --csv", "tables -o", "calibrate -o", "ros-station --report"])
def test_no_output_follows_a_link_planted_in_a_sticky_directory(tmp_path: Path, command: str,
                                                                capsys: pytest.CaptureFixture[str]) -> None:
    link, victim = _planted_link(tmp_path, "out")
    argv = {
        "plan --csv": ["plan", "--start", "1", "--end", "3", "--no-collision", "--csv", str(link)],
        "tables -o": ["tables", "lab_sim", "--key", "sim_pos", "-o", str(link)],
        "calibrate -o": ["calibrate", "--from-table", str(LAB_TABLE), "--key", "real_pos", "--base", "lab_real",
                         "-o", str(link)],
        "ros-station --report": ["ros-station", "--duration", "0.5", "--master", "http://127.0.0.1:9/",
                                 "--report", str(link)],
    }[command]
    assert main(argv) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert f"cannot write {link}: {link} is a symbolic link of user 'nobody' (uid 65534) in the shared sticky" in err
    assert victim.read_text() == "precious\n"
    assert sorted(p.name for p in link.parent.iterdir()) == ["out"]


@pytest.mark.parametrize("argv", [
    ["tables", "lab_sim", "--key", "sim_pos", "-o", "-"],
    ["calibrate", "--from-table", str(LAB_TABLE), "--key", "real_pos", "--base", "lab_real", "-o", "-"],
    ["plan", "--start", "1", "--end", "3", "--csv", "-"],
    ["solve", "--start", "1", "--end", "3", "--video", "-"],
    ["solve", "--start", "1", "--end", "3", "--frames", "-"],
])
def test_dash_as_an_output_is_refused_in_one_line(argv: list[str], tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                  capsys: pytest.CaptureFixture[str]) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = _one_error_line(capsys.readouterr().err)
    assert "cannot write -: standard output is not supported for this output: give a file name (./- for" in err
    assert _listing(tmp_path) == []


@pytest.mark.parametrize(("target", "expected"), [
    ("/proc/x.mp4", "the directory /proc does not accept new files"),
    ("{tmp}/missing/x.mp4", "missing does not exist"),
])
@pytest.mark.parametrize("option", ["--video", "--frames"])
def test_unwritable_render_outputs_fail_before_the_run(tmp_path: Path, target: str, expected: str, option: str,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    target = target.format(tmp=tmp_path)
    if option == "--frames":
        target = target.removesuffix(".mp4")
    assert main(["solve", "--start", "1", "--end", "3", "--blocks", "1", option, target]) == 2
    err = _one_error_line(capsys.readouterr().err)  # no progress line: nothing was simulated
    assert err.startswith(f"ur3hanoi: error: cannot write {target}: ") and expected in err
    assert _listing(tmp_path) == []


def test_a_video_named_like_an_ffmpeg_option_is_a_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
                                                       capsys: pytest.CaptureFixture[str]) -> None:
    import imageio_ffmpeg

    monkeypatch.chdir(tmp_path)
    assert main(["solve", "--start", "1", "--end", "3", "--blocks", "1", "--video=-x.mp4", "--size", "32x24",
                 "--fps", "5", "--to", "0.6"]) == 0
    assert "wrote 4 frames to -x.mp4" in capsys.readouterr().out
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / "-x.mp4"))[0] == 4
    assert _listing(tmp_path) == ["-x.mp4"]


@pytest.mark.ros
@requires_ros
def test_ros_station_report_dash_is_standard_output(tmp_path: Path) -> None:
    env = ros_env(free_port(), tmp_path)
    result = run(ur3hanoi_cmd("ros-station", "--duration", "1", "--report", "-"), env, 120.0)
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    report = json.loads("\n".join(lines[lines.index("{"):]))  # the JSON report (info lines may precede it)
    assert report["control"]["cycles"] > 0 and report["reports_written"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["ros_home"]  # no file named '-'


@pytest.mark.parametrize("option", ["--video", "--frames"])
def test_ctrl_c_during_a_rendered_solve_leaves_the_old_output(option: str, tmp_path: Path,
                                                              monkeypatch: pytest.MonkeyPatch,
                                                              capsys: pytest.CaptureFixture[str]) -> None:

    real = progress.ProgressLines.__call__

    def interrupt_halfway(self: progress.ProgressLines, fraction: float, label: str) -> None:
        real(self, fraction, label)
        # Frames rendered (during the run, or by the parallel workers after it): then Ctrl-C.
        if fraction >= 0.5 and (getattr(self.recorder, "count", 0) > 0 or "frame" in label):
            raise KeyboardInterrupt

    monkeypatch.setattr(progress.ProgressLines, "__call__", interrupt_halfway)
    out = tmp_path / ("run.mp4" if option == "--video" else "frames")
    if option == "--video":
        out.write_bytes(b"the previous video")
    else:
        out.mkdir()
        (out / "frame_00000.png").write_bytes(b"the previous frame")
    assert main(["solve", "--start", "1", "--end", "3", "--blocks", "1", option, str(out), "--size", "32x24",
                 "--fps", "5"]) == 130
    assert "interrupted" in capsys.readouterr().err
    if option == "--video":
        assert out.read_bytes() == b"the previous video"
    else:
        assert {p.name: p.read_bytes() for p in out.iterdir()} == {"frame_00000.png": b"the previous frame"}
    assert _listing(tmp_path) == [out.name]
