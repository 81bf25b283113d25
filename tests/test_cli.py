"""The `ur3hanoi` command: exit codes, one-line errors, and the guarantee that failures write nothing."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
import yaml

from ur3hanoi.cli import main

from .conftest import LAB_REAL, LAB_SIM, REPO


def _bad_calibration(tmp_path: Path, **grid: object) -> Path:
    raw = yaml.safe_load(LAB_REAL.read_text())
    raw["grid"].update(grid)
    path = tmp_path / "bad_station.yaml"
    path.write_text(yaml.safe_dump(raw))
    return path


def test_tables_writes_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(LAB_SIM), "--key", "sim_pos", "-o", str(out), "--solver", "placo"]) == 0
    assert "wrote sim_pos" in capsys.readouterr().out
    assert "placo IK" in out.read_text()


def test_unreachable_grid_exits_2_with_one_line_and_writes_nothing(tmp_path: Path,
                                                                   capsys: pytest.CaptureFixture[str]) -> None:
    cal = _bad_calibration(tmp_path, tower_origins=[[0.25, -0.20, 0.0288], [0.25, -0.09, 0.0288],
                                                    [0.95, 0.04, 0.0288]])
    out = tmp_path / "lab2_data.yaml"
    assert main(["tables", str(cal), "--key", "real_pos", "-o", str(out)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert "tower 2 height 0 on" in err and "unreachable" in err and "target xyz" in err and "residual" in err
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


def test_missing_calibration_exits_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["tables", str(tmp_path / "nope.yaml"), "--key", "sim_pos", "-o", str(tmp_path / "o.yaml")]) == 2
    assert "nope.yaml" in capsys.readouterr().err


def test_bad_key_is_an_argparse_error(tmp_path: Path) -> None:
    with pytest.raises(SystemExit) as info:
        main(["tables", str(LAB_SIM), "--key", "gazebo", "-o", str(tmp_path / "o.yaml")])
    assert info.value.code == 2


def test_check_table_ok_and_fail(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    table = REPO / "tables/lab2_data.yaml"
    assert main(["check-table", str(table), "--key", "real_pos", "--calibration", str(LAB_REAL)]) == 0
    assert "18/18 entries within 1.0 mm / 0.5 deg" in capsys.readouterr().out
    # The same joints judged against another station's grid are far off: exit 1.
    assert main(["check-table", str(table), "--key", "real_pos", "--calibration", str(LAB_SIM)]) == 1
    assert "0/18 entries" in capsys.readouterr().out


def test_check_table_on_hand_recorded_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    data = yaml.safe_load((REPO / "tables/lab2_data.yaml").read_text())
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


def test_check_table_missing_key_exits_2(capsys: pytest.CaptureFixture[str]) -> None:
    table = REPO / "tables/lab2_data.yaml"
    assert main(["check-table", str(table), "--key", "gazebo_pos", "--calibration", str(LAB_REAL)]) == 2
    assert "key 'gazebo_pos' not found" in capsys.readouterr().err


def test_console_script_entry_point() -> None:
    out = subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "--version"], capture_output=True, text=True,
                         check=True)
    assert out.stdout.startswith("ur3hanoi ")


def test_readme_cli_reference_is_up_to_date() -> None:
    sys.path.insert(0, str(REPO / "tools"))
    try:
        from update_readme_cli import render
    finally:
        sys.path.pop(0)
    readme = (REPO / "README.md").read_text()
    assert render(readme) == readme, "README CLI reference is stale: run `make docs`"
