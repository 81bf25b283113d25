"""`ur3hanoi solve --table FILE --key KEY`: simulate a given table's waypoints (exit 0 solved, 3 a missed block,
2 a table or option that cannot be used)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support.table_helpers import COURSE_LIKE_OFFSET_M, shifted_table, table_yaml, with_bad_entry
from ur3hanoi import cli
from ur3hanoi.station.calibration import Station


@pytest.fixture(scope="module")
def course_like(tmp_path_factory: pytest.TempPathFactory) -> Path:
    from ur3hanoi.station.calibration import load_station

    path = tmp_path_factory.mktemp("tables") / "lab2_data.yaml"
    path.write_text(table_yaml(shifted_table(load_station("lab_sim"))))
    return path


def test_a_course_like_table_solves_json(course_like: Path, capsys: pytest.CaptureFixture[str]) -> None:
    code = cli.main(["solve", "--start", "1", "--end", "3", "--table", str(course_like), "--key", "sim_pos",
                     "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 0 and out["status"] == "solved" and out["moves_completed"] == 7, captured.err
    assert out["table"] == {"file": str(course_like), "key": "sim_pos"}
    assert [(b["block"], b["tower"], b["height"]) for b in out["final_blocks"]] == [(1, 3, 1), (2, 3, 2), (3, 3, 3)]
    assert captured.err == ""


def test_the_summary_says_which_table_was_followed(course_like: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "2", "--end", "1", "--blocks", "2", "--table", str(course_like),
                     "--key", "sim_pos", "--calibration", "lab_sim"]) == 0
    first = capsys.readouterr().out.splitlines()[0]
    assert first == (f"solved: 3/3 moves, tower 2 -> 1, 2 blocks on lab_sim, following {course_like}:sim_pos "
                     "(suction profile lab_sim)")


def test_a_table_entry_15_mm_off_exits_3_naming_it(lab_sim: Station, tmp_path: Path,
                                                    capsys: pytest.CaptureFixture[str]) -> None:
    good = shifted_table(lab_sim)
    bad = with_bad_entry(good, lab_sim, (0, 2, 0), (0.015, COURSE_LIKE_OFFSET_M[1], 0.0))
    path = tmp_path / "bad.yaml"
    path.write_text(table_yaml(bad))
    code = cli.main(["solve", "--start", "1", "--end", "3", "--table", str(path), "--key", "sim_pos", "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)
    assert code == 3 and out["status"] == "halted" and out["fault"]["move"] == 1
    assert captured.err == f"ur3hanoi: error: {out['error']}\n"
    assert "table entry tower 1 height 3 on (Q[0][2][0])" in out["error"] and " 15.6 mm " in out["error"]


def test_a_null_entry_the_solve_needs_exits_2_naming_it(lab_sim: Station, tmp_path: Path,
                                                        capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "holes.yaml"
    path.write_text(table_yaml(shifted_table(lab_sim), missing=[(0, 1, 1)]))
    code = cli.main(["solve", "--start", "1", "--end", "3", "--table", str(path), "--key", "sim_pos"])
    captured = capsys.readouterr()
    assert code == 2 and captured.out == ""
    # Missing entries are read (students record tables with holes); the plan names the one the solve visits.
    assert captured.err.startswith("ur3hanoi: error: ") and captured.err.count("\n") == 1
    assert "1 table entry the solve needs is missing: tower 1 height 2 above (Q[0][1][1])" in captured.err


def test_missing_entries_the_solve_does_not_visit_are_fine(lab_sim: Station, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "holes.yaml"
    # Tower 1 -> 3 with 3 blocks never goes to tower 2's top slot.
    path.write_text(table_yaml(shifted_table(lab_sim), missing=[(1, 2, 0), (1, 2, 1)]))
    code = cli.main(["solve", "--start", "1", "--end", "3", "--table", str(path), "--key", "sim_pos"])
    assert code == 0, capsys.readouterr().err


def test_a_table_of_another_grid_exits_2(lab_sim: Station, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "small.yaml"
    path.write_text(table_yaml(shifted_table(lab_sim)[:, :2]))
    assert cli.main(["solve", "--start", "1", "--end", "3", "--table", str(path), "--key", "sim_pos"]) == 2
    assert "shape (3, 2, 2, 6)" in capsys.readouterr().err


@pytest.mark.parametrize(("args", "message"), [
    (["--key", "real_pos"], "--key real_pos needs --calibration CAL"),
    ([], "--table needs --key (sim_pos or real_pos)"),
], ids=["real-needs-calibration", "table-needs-key"])
def test_table_options_that_do_not_fit_exit_2(course_like: Path, args: list[str], message: str,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "3", "--table", str(course_like), *args]) == 2
    assert message in capsys.readouterr().err


def test_key_without_table_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "3", "--key", "sim_pos"]) == 2
    assert "use with --table FILE" in capsys.readouterr().err


def test_a_key_the_file_lacks_exits_2(course_like: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "3", "--table", str(course_like), "--key", "real_pos",
                     "--calibration", "lab_real"]) == 2
    assert "key 'real_pos' not found" in capsys.readouterr().err


def test_the_video_cannot_overwrite_the_table(course_like: Path, tmp_path: Path,
                                              capsys: pytest.CaptureFixture[str]) -> None:
    link = tmp_path / "table.mp4"
    link.symlink_to(course_like)
    before = course_like.read_bytes()
    assert cli.main(["solve", "--start", "1", "--end", "3", "--table", str(course_like), "--key", "sim_pos",
                     "--video", str(link)]) == 2
    assert course_like.read_bytes() == before and "it is also an input of this command" in capsys.readouterr().err
