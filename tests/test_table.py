"""lab2_data.yaml: generation, the course format, in-place updates that keep other keys, atomicity, staleness."""

from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml

from ur3hanoi.cli import main
from ur3hanoi.errors import TableError
from ur3hanoi.grid import T_world_tcp
from ur3hanoi.ik import pose_errors
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station
from ur3hanoi.table import check_table, generate_table, parse_q, read_table, write_table

from .conftest import LAB_REAL, LAB_SIM, REPO

HAND_RECORDED = """\
# recorded by hand on station 4, 2025-10-02
real_pos:
  - - - [1.0, -1.5, 2.0, -2.0, -1.5707, 0.3]    # A bottom, on
      - [1.0, -1.6, 1.9, -1.8, -1.5707, 0.3]
block_xy_pos: [[[0.2, 0.05]]]   # odd flow style, kept as is
notes: {station: 4, by: "TA"}
"""


def _regenerate(out: Path) -> None:
    """The exact commands that produce tables/lab2_data.yaml (see the Makefile's `tables` target)."""
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(out)]) == 0
    assert main(["tables", "lab_real", "--key", "real_pos", "-o", str(out)]) == 0


def test_shipped_table_is_not_stale(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    fresh = tmp_path / "lab2_data.yaml"
    _regenerate(fresh)
    assert fresh.read_bytes() == (REPO / "tables/lab2_data.yaml").read_bytes(), (
        "tables/lab2_data.yaml is stale: run `make tables`"
    )


def test_course_format_and_order(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    table = generate_table(lab_sim)
    write_table(out, table, "sim_pos")
    data = yaml.safe_load(out.read_text())
    Q = data["sim_pos"]
    assert len(Q) == 3 and all(len(t) == 3 for t in Q) and all(len(p) == 2 for t in Q for p in t)
    robot = load_ur3(lab_sim.tool, lab_sim.limits)
    for t in range(3):
        for h in range(3):
            for k in (0, 1):
                assert len(Q[t][h][k]) == 6
                T = lab_sim.T_world_base * robot.fk(np.array(Q[t][h][k]))
                dp, dr = pose_errors(T, T_world_tcp(lab_sim, t, h, k))
                assert dp <= 1e-9 and dr <= 1e-9
            # k = 0 is the contact pose: lower than k = 1 by the approach distance.
            z_on = (lab_sim.T_world_base * robot.fk(np.array(Q[t][h][0]))).translation[2]
            z_above = (lab_sim.T_world_base * robot.fk(np.array(Q[t][h][1]))).translation[2]
            assert z_above - z_on == pytest.approx(0.096, abs=1e-9)
    assert data["block_xy_pos"][1][2] == pytest.approx([0.20, 0.15])


def test_every_table_pose_accuracy_in_written_file(shipped_station: Station, tmp_path: Path) -> None:
    out = tmp_path / "t.yaml"
    write_table(out, generate_table(shipped_station), "real_pos")
    rows = check_table(read_table(out, "real_pos"), shipped_station)
    assert max(r.position_error_mm for r in rows) <= 1e-6  # 1e-9 m
    assert max(r.orientation_error_deg for r in rows) <= math.degrees(1e-9)


def test_stacked_layout_writes_no_block_xy(lab_real: Station, tmp_path: Path) -> None:
    out = tmp_path / "t.yaml"
    write_table(out, generate_table(lab_real), "real_pos")
    assert set(yaml.safe_load(out.read_text())) == {"real_pos"}


def test_other_keys_kept_byte_for_byte(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text(HAND_RECORDED)
    write_table(out, generate_table(lab_sim), "sim_pos")
    text = out.read_text()
    # real_pos and notes keep their exact text, comments included.
    assert "real_pos:\n  - - - [1.0, -1.5, 2.0, -2.0, -1.5707, 0.3]    # A bottom, on\n" in text
    assert 'notes: {station: 4, by: "TA"}\n' in text
    assert "# recorded by hand on station 4, 2025-10-02" in text
    data = yaml.safe_load(text)
    assert data["real_pos"] == yaml.safe_load(HAND_RECORDED)["real_pos"]
    # block_xy_pos is regenerated for the flat layout.
    assert np.array(data["block_xy_pos"]).shape == (3, 3, 2)


def test_regenerating_real_pos_leaves_sim_pos_and_block_xy(lab_sim: Station, lab_real: Station,
                                                           tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    write_table(out, generate_table(lab_sim), "sim_pos")
    before = yaml.safe_load(out.read_text())
    sim_text = out.read_text().split("block_xy_pos:")[0].split("sim_pos:")[1]
    write_table(out, generate_table(lab_real), "real_pos")
    after_text = out.read_text()
    assert sim_text in after_text
    after = yaml.safe_load(after_text)
    assert after["sim_pos"] == before["sim_pos"]
    assert after["block_xy_pos"] == before["block_xy_pos"]
    assert "real_pos generated from" in after_text and "sim_pos generated from" in after_text


def test_output_is_deterministic(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    a, b = tmp_path / "a.yaml", tmp_path / "b.yaml"
    _regenerate(a)
    _regenerate(b)
    assert a.read_bytes() == b.read_bytes()
    _regenerate(a)  # regenerating an existing file is idempotent
    assert a.read_bytes() == b.read_bytes()


def test_failed_write_leaves_old_file_identical(lab_sim: Station, tmp_path: Path,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text(HAND_RECORDED)
    before = out.read_bytes()

    def boom(src: str, dst: str) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", boom)
    with pytest.raises(OSError):
        write_table(out, generate_table(lab_sim), "sim_pos")
    assert out.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab2_data.yaml"]  # no temp file left behind


def test_unparseable_existing_file_is_not_touched(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text("real_pos: [unclosed\n")
    before = out.read_bytes()
    with pytest.raises(TableError, match="not valid YAML"):
        write_table(out, generate_table(lab_sim), "sim_pos")
    assert out.read_bytes() == before


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("nope", "expected a list"),
        ([[[[0.0] * 6]]], r"\[0\]\[0\]: expected 2 poses"),
        ([[[[0.0] * 5, [0.0] * 6]]], r"\[0\]\[0\]\[0\]: expected 6 finite joint angles"),
        ([[[[0.0] * 5 + [float("nan")], [0.0] * 6]]], r"\[0\]\[0\]\[0\]: expected 6 finite"),
        ([[[[0.0] * 6, [0.0] * 6]], [[[0.0] * 6, [0.0] * 6]] * 2], r"\[1\]: has 2 heights"),
    ],
)
def test_parse_q_errors_name_the_entry(value: object, match: str) -> None:
    with pytest.raises(TableError, match=match):
        parse_q(value, "f.yaml:real_pos")


def test_check_table_flags_a_bad_entry(lab_real: Station) -> None:
    q = generate_table(lab_real).q.copy()
    q[1, 2, 0, 1] += 0.01  # 10 mrad on the shoulder: several mm at the tool
    rows = check_table(q, lab_real)
    bad = [r for r in rows if not r.ok]
    assert [(r.tower, r.height, r.k) for r in bad] == [(1, 2, 0)]
    assert bad[0].position_error_mm > 1.0


def test_check_table_shape_mismatch(lab_real: Station) -> None:
    with pytest.raises(TableError, match="2 towers x 3 heights"):
        check_table(np.zeros((2, 3, 2, 6)), lab_real)


def test_calibration_files_untouched_by_generation(tmp_path: Path) -> None:
    for src in (LAB_SIM, LAB_REAL):
        copy = tmp_path / src.name
        shutil.copy(src, copy)
        before = copy.read_bytes()
        assert main(["tables", str(copy), "--key", "real_pos", "-o", str(tmp_path / "o.yaml")]) == 0
        assert copy.read_bytes() == before


def test_new_file_gets_umask_permissions_existing_keeps_its_own(lab_real: Station, tmp_path: Path) -> None:
    umask = os.umask(0o022)
    try:
        out = tmp_path / "new.yaml"
        write_table(out, generate_table(lab_real), "real_pos")
        assert out.stat().st_mode & 0o777 == 0o644
        out.chmod(0o600)
        write_table(out, generate_table(lab_real), "real_pos")
        assert out.stat().st_mode & 0o777 == 0o600
    finally:
        os.umask(umask)
