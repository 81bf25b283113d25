"""``ur3hanoi teach`` without a driver: bad input gets one line and leaves TAUGHT as it was; ``--finish`` writes
the calibration and the table key (keeping the lab file's other keys) from a taught file; no terminal, no
session. The sessions themselves run against the real stations: tests/teach/test_ros.py, tests/teach/test_dds.py."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from ur3hanoi.cli import main
from ur3hanoi.station.calibration import load_station
from ur3hanoi.tables import read_recorded_table
from ur3hanoi.tables.ik_table import generate_table
from ur3hanoi.teach.taught_file import open_taught

TAUGHT = "units: deg\npoints:\n  - {tower: 1, height: 1, q: [110.87, -64.65, 136.28, -161.63, -90, 20.87]}\n"


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("ur3hanoi: error: "), err
    return lines[0]


def test_without_a_terminal_it_says_what_to_do_and_touches_nothing(tmp_path: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    taught = tmp_path / "t.yaml"
    taught.write_text(TAUGHT)
    # pytest's stdin is not a terminal
    assert main(["teach", "--via", "ros", "--base", "lab_real", "-o", str(taught)]) == 2
    line = one_line(capsys.readouterr().err)
    assert "stdin is not a terminal" in line and "--record-now T,H" in line and "--finish" in line
    assert taught.read_text() == TAUGHT


@pytest.mark.parametrize(("argv", "message"), [
    (["--key", "real_pos"], "--key is only used with --table"),
    (["--via", "ros2", "--master", "http://127.0.0.1:1"], "--master is only used with --via ros"),
    (["--start", "4"], "--start 4 is invalid: expected a tower 1..3 (lab_real_example has 3 towers)"),
    (["--record-now", "1,4"], "--record-now height 4 is invalid: expected a height 1..3"),
    (["--record-now", "one"], "argument --record-now: 'one' is invalid: expected TOWER,HEIGHT"),
    (["--wait", "0"], "argument --wait: '0' is invalid: expected a wait for the driver [s] in [0.5, 600]"),
])
def test_bad_options_get_one_line(argv: list[str], message: str, tmp_path: Path,
                                  capsys: pytest.CaptureFixture[str]) -> None:
    args = ["teach", "--via", "ros", "--base", "lab_real", "-o", str(tmp_path / "t.yaml"), *argv]
    assert main(args) == 2
    assert message in one_line(capsys.readouterr().err)
    assert not (tmp_path / "t.yaml").exists()


@pytest.mark.parametrize(("base", "taught", "message"), [
    ("ur3hanoi/station/shipped/taught_example.yaml", None, "taught_example.yaml"),  # a base calibration that is not one
    ("lab_real", 'units: deg\nstation: "other"\npoints:\n  - {tower: 1, height: 1, q: [110, -64, 136, -161, -90, 2]}\n',
     "taught for station 'other', not for 'lab_real_example'"),
    ("lab_real", TAUGHT.replace("deg", "rad").replace("110.87, -64.65, 136.28, -161.63, -90, 20.87",
                                                        "1.93, -1.13, 2.38, -2.82, -1.57, 0.36"),
     "units: rad: teach records degrees"),
])
def test_a_bad_base_or_taught_file_gets_one_line_and_the_file_stays(base: str, taught: str | None, message: str,
                                                                    tmp_path: Path, repo: Path,
                                                                    capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "t.yaml"
    if taught is not None:
        out.write_text(taught)
    base_ref = str(repo / base) if base.endswith(".yaml") else base
    assert main(["teach", "--via", "ros", "--base", base_ref, "-o", str(out), "--finish"]) == 2
    assert message in one_line(capsys.readouterr().err)
    assert (out.read_text() == taught) if taught is not None else not out.exists()


def test_finish_writes_the_calibration_the_table_key_and_the_next_command(tmp_path: Path,
                                                                          capsys: pytest.CaptureFixture[str]) -> None:
    base = load_station("lab_real")
    q = generate_table(base).q
    f = open_taught(tmp_path / "t.yaml", base, "lab_real")
    for t, h in ((0, 2), (1, 0), (2, 0)):
        f = f.with_point(t, h, tuple(q[t, h, 0]))[0]
    f.save()
    lab = tmp_path / "lab2_data.yaml"
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(lab)]) == 0
    sim_before = read_recorded_table(lab, "sim_pos").q
    capsys.readouterr()
    code = main(["teach", "--via", "ros", "--base", "lab_real", "-o", str(f.path), "--table", str(lab), "--finish"])
    out = capsys.readouterr().out
    assert code == 0
    station = load_station(tmp_path / "t_station.yaml")
    assert np.allclose(station.tower_origins, base.tower_origins, atol=5e-6)
    assert np.array_equal(read_recorded_table(lab, "sim_pos").q, sim_before)  # the other key is kept
    assert np.allclose(read_recorded_table(lab, "real_pos").q, generate_table(station).q, atol=1e-12)
    assert "3/3 entries within" in out and "an exact fit (one point per tower)" in out
    assert f"wrote real_pos (3 towers x 3 heights x 2) to {lab}" in out
    assert (f"ur3hanoi ros-solve --table {lab} --key real_pos --calibration {tmp_path / 't_station.yaml'} --start 1 "
            "--end 3 --v 0.5 --a 0.5") in out


def test_finish_with_a_tower_missing_says_which(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "t.yaml"
    out.write_text(TAUGHT)
    assert main(["teach", "--via", "ros2", "--base", "lab_real", "-o", str(out), "--finish"]) == 2
    assert "tower(s) 2, 3 have none" in one_line(capsys.readouterr().err)
    assert out.read_text() == TAUGHT and not (tmp_path / "t_station.yaml").exists()


def test_finish_refuses_a_wrong_point_that_is_its_tower_s_only_contact(tmp_path: Path,
                                                                         capsys: pytest.CaptureFixture[str]) -> None:
    base = load_station("lab_real")
    q = generate_table(base).q
    f = open_taught(tmp_path / "t.yaml", base, "lab_real")
    for (t, h), qi in zip(((0, 2), (1, 0), (2, 0)), (q[0, 2, 0], base.q_home_array, q[2, 0, 0]), strict=True):
        f = f.with_point(t, h, tuple(float(v) for v in qi))[0]  # tower 2 recorded with the arm at home
    f.save()
    before = f.path.read_text()
    assert main(["teach", "--via", "ros", "--base", "lab_real", "-o", str(f.path), "--finish"]) == 2
    line = one_line(capsys.readouterr().err)
    assert "nothing written: tower 2 height 1 [points[1]] is " in line and "the arm was at home" in line
    assert f.path.read_text() == before and not (tmp_path / "t_station.yaml").exists()


def test_finish_writes_a_tower_where_the_student_put_it(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Issue 37: a tower 25 mm along the row from the base layout is the station's own, written with the note that
    a single pose cannot show a sideways error (and which pose would)."""
    base = load_station("lab_real")
    o = list(base.tower_origins)
    o[2] = (o[2][0], o[2][1] + 0.025, o[2][2])  # tower 3 stands 25 mm further along the row
    q = generate_table(base.with_grid(o, base.height_step, base.tool_yaw)).q
    f = open_taught(tmp_path / "t.yaml", base, "lab_real")
    for t, h in ((0, 2), (1, 0), (2, 0)):
        f = f.with_point(t, h, tuple(float(v) for v in q[t, h, 0]))[0]
    f.save()
    argv = ["teach", "--via", "ros", "--base", "lab_real", "-o", str(f.path), "--finish"]
    assert main(argv) == 0
    out = " ".join(capsys.readouterr().out.split())
    assert "tower 3 rests on one pose, tower 3 height 1 [points[2]]" in out
    assert "record tower 3 height 1 above (or a second height of tower 3) to check it" in out
    np.testing.assert_allclose(load_station(tmp_path / "t_station.yaml").tower_origins, o, atol=1e-6)
