"""lab2_data.yaml: the course format, strict reading, in-place updates that keep other keys, atomicity, locking."""

from __future__ import annotations

import multiprocessing
import os
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml

from ur3hanoi.cli import main
from ur3hanoi.errors import OutputError, TableError
from ur3hanoi.grid import T_world_tcp
from ur3hanoi.ik import pose_errors
from ur3hanoi.labfile import parse_q, read_lab_file, read_recorded_table, read_table, write_table
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station
from ur3hanoi.waypoints import generate_table

from .conftest import LAB_REAL, LAB_SIM, REPO

HAND_RECORDED = """\
# recorded by hand on station 4, 2025-10-02
real_pos:
  - - - [1.0, -1.5, 2.0, -2.0, -1.5707, 0.3]    # A bottom, on
      - [1.0, -1.6, 1.9, -1.8, -1.5707, 0.3]
block_xy_pos: [[[0.2, 0.05]]]   # odd flow style
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


def test_stacked_layout_writes_no_block_xy(lab_real: Station, tmp_path: Path) -> None:
    out = tmp_path / "t.yaml"
    write_table(out, generate_table(lab_real), "real_pos")
    assert set(yaml.safe_load(out.read_text())) == {"real_pos"}


def test_other_keys_kept_byte_for_byte(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text(HAND_RECORDED)
    write_table(out, generate_table(lab_sim), "sim_pos")
    text = out.read_text()
    # real_pos keeps its exact text, comments included.
    assert "real_pos:\n  - - - [1.0, -1.5, 2.0, -2.0, -1.5707, 0.3]    # A bottom, on\n" in text
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

    def disk_full(fd: int) -> None:
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "fsync", disk_full)
    with pytest.raises(OutputError, match="No space left on device"):
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
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab2_data.yaml"]


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("nope", r"field 'real_pos' = 'nope' is invalid: expected a list of 1..10 towers"),
        ([[[[0.0] * 6] * 3]], r"field 'real_pos\[0\]\[0\]' .* expected a list of 1..2 poses \[on, above\]"),
        ([[[[0.0] * 6]]], r"1 of 2 entries are missing \(tower 1 height 1 above\): this needs a complete table"),
        ([[[[0.0] * 5, [0.0] * 6]]], r"field 'real_pos\[0\]\[0\]\[0\]' .* expected a list of 6 numbers"),
        ([[[[0.0] * 5 + [float("nan")], [0.0] * 6]]], r"field 'real_pos\[0\]\[0\]\[0\]\[5\]' = nan"),
        ([[[[0.0] * 5 + [10**400], [0.0] * 6]]], r"real_pos\[0\]\[0\]\[0\]\[5\]' = 1000.*0 is invalid"),
        ([[[[0.0] * 5 + [120.0], [0.0] * 6]]],
         r"= 120.0 is invalid: expected a joint angle \[rad\] in \[-6.28319, 6.28319\]"),
        ([[[[0.0] * 6, [0.0] * 6]], [[[0.0] * 6, [0.0] * 6]] * 2], r"field 'real_pos\[1\]' .* 1 heights like"),
    ],
    ids=["not-a-list", "three-poses", "on-only", "five-joints", "nan", "huge-int", "degrees", "ragged"],
)
def test_parse_q_errors_name_the_entry(value: object, match: str) -> None:
    with pytest.raises(TableError, match=match) as info:
        parse_q(value, "f.yaml", "real_pos")
    assert str(info.value).startswith("f.yaml")
    assert len(str(info.value)) < 300


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("sim_pos: []\n\"sim_pos\": []\n", r"duplicate key 'sim_pos' \(first given on line 1\) \(line 2"),
        ("sim_pso: [[[[0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]]]]\n",
         r"field 'sim_pso' is unknown: did you mean 'sim_pos'\?"),
        ("notes: {station: 4}\n", r"field 'notes' is unknown: expected one of sim_pos, real_pos, block_xy_pos"),
        ("- 1\n", r"expected a mapping with keys sim_pos, real_pos, block_xy_pos, got a list"),
        ("block_xy_pos: [[[0.2, .inf]]]\n", r"field 'block_xy_pos\[0\]\[0\]\[1\]' = inf is invalid"),
    ],
    ids=["duplicate", "typo", "unknown", "not-a-mapping", "inf"],
)
def test_strict_lab_file(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "lab2_data.yaml"
    path.write_text(text)
    with pytest.raises(TableError, match=match):
        read_lab_file(path)


def test_existing_invalid_file_is_not_updated(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text("real_pos: []\nreal_pos: []\n")
    before = out.read_bytes()
    with pytest.raises(TableError, match="duplicate key 'real_pos'"):
        write_table(out, generate_table(lab_sim), "sim_pos")
    assert out.read_bytes() == before


def test_quoted_key_is_replaced_not_duplicated(lab_real: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text('"real_pos": [[[[0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]]]]\n')
    write_table(out, generate_table(lab_real), "real_pos")
    np.testing.assert_array_equal(read_table(out, "real_pos"), generate_table(lab_real).q)
    assert out.read_text().count("real_pos:") == 1


def test_read_table_missing_key(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text("block_xy_pos: [[[0.2, 0.05]]]\n")
    with pytest.raises(TableError, match="key 'real_pos' not found"):
        read_table(path, "real_pos")


def test_header_stays_a_comment_with_control_characters_in_the_label(lab_real: Station, tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    write_table(out, generate_table(lab_real), "real_pos", calibration_label="evil\nreal_pos: 1\r\x1b[2J\u2028x")
    lab = read_lab_file(out)  # still strict-valid YAML: the label did not inject a key or a line break
    assert set(lab.data) == {"real_pos"}
    header = [line for line in lab.text.splitlines() if "generated from" in line]
    assert header == [line for line in header if line.startswith("# ")] and len(header) == 1
    assert "evil\\nreal_pos: 1\\r\\x1b[2J\\u2028x" in header[0]


def test_symlinked_output_is_written_through(lab_real: Station, tmp_path: Path) -> None:
    target = tmp_path / "real" / "lab2_data.yaml"
    target.parent.mkdir()
    link = tmp_path / "link.yaml"
    link.symlink_to(target)
    write_table(link, generate_table(lab_real), "real_pos")
    assert link.is_symlink() and target.is_file()
    np.testing.assert_array_equal(read_table(target, "real_pos"), generate_table(lab_real).q)
    assert sorted(p.name for p in target.parent.iterdir()) == ["lab2_data.yaml"]


def test_output_that_is_the_calibration_is_refused(tmp_path: Path) -> None:
    cal = tmp_path / "station.yaml"
    shutil.copy(LAB_REAL, cal)
    before = cal.read_bytes()
    from ur3hanoi.station import load_station

    with pytest.raises(OutputError, match="it is also an input of this command"):
        write_table(cal, generate_table(load_station(cal)), "real_pos")
    assert cal.read_bytes() == before


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


_TABLES: dict[str, Any] = {}


def _table_writer(path: str, key: str, rounds: int, barrier: Any) -> None:
    for _ in range(rounds):
        barrier.wait()
        write_table(path, _TABLES[key], key)
        barrier.wait()


def test_concurrent_tables_runs_never_lose_a_key(lab_sim: Station, lab_real: Station, tmp_path: Path) -> None:
    # 8 writers (4 per key) into one file, 20 rounds from an empty file: both keys must be there every time.
    _TABLES.update(sim_pos=generate_table(lab_sim), real_pos=generate_table(lab_real))
    path = tmp_path / "lab2_data.yaml"
    rounds, keys = 20, ["sim_pos", "real_pos"] * 4
    ctx = multiprocessing.get_context("fork")  # the children reuse the generated tables
    barrier = ctx.Barrier(len(keys) + 1)
    procs = [ctx.Process(target=_table_writer, args=(str(path), key, rounds, barrier)) for key in keys]
    for p in procs:
        p.start()
    seen = []
    try:
        for _ in range(rounds):
            barrier.wait(timeout=60)  # start the round
            barrier.wait(timeout=60)  # every writer is done
            seen.append(sorted(read_lab_file(path).data))
            path.unlink()
    finally:
        for p in procs:
            p.join(timeout=60)
    assert [p.exitcode for p in procs] == [0] * len(keys)
    assert seen == [["block_xy_pos", "real_pos", "sim_pos"]] * rounds
    assert _listing(tmp_path) == []


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


# ------------------------------------------------------------------------------------------- recorded tables

ON_Q = [2.1, -1.2, 1.8, -2.2, -1.57, 0.5]
ABOVE_Q = [2.1, -1.4, 1.6, -1.8, -1.57, 0.5]


def test_generated_comments_number_towers_and_heights_from_1(lab_sim: Station, tmp_path: Path) -> None:
    out = tmp_path / "t.yaml"
    text = write_table(out, generate_table(lab_sim), "sim_pos")
    assert "]  # tower 1 height 1 on\n" in text and "]  # tower 3 height 3 above\n" in text
    assert "# tower 3 height 3 [m, world]" in text
    assert "tower 0" not in text and "height 0" not in text


def test_recorded_table_marks_missing_entries_in_every_form(tmp_path: Path) -> None:
    # tower 1: [on] only (above left out) and a null above; tower 2: a null slot; tower 3: null.
    doc = {"real_pos": [[[ON_Q], [ON_Q, None], [ON_Q, ABOVE_Q]], [[ON_Q, ABOVE_Q], None, [ON_Q, ABOVE_Q]], None]}
    path = tmp_path / "t.yaml"
    path.write_text(yaml.safe_dump(doc))
    rec = read_recorded_table(path, "real_pos")
    assert rec.q.shape == (3, 3, 2, 6)
    assert rec.missing == ((0, 0, 1), (0, 1, 1), (1, 1, 0), (1, 1, 1), (2, 0, 0), (2, 0, 1), (2, 1, 0), (2, 1, 1),
                           (2, 2, 0), (2, 2, 1))
    assert rec.present.sum() == 8 and np.isnan(rec.q[~rec.present]).all()
    np.testing.assert_array_equal(rec.q[0, 2, 1], ABOVE_Q)
    with pytest.raises(TableError, match=r"t.yaml:real_pos: 10 of 18 entries are missing \(tower 1 height 1 above, "
                                         r"tower 1 height 2 above, tower 2 height 2 on, .* and 4 more\): this needs a "
                                         r"complete table"):
        read_table(path, "real_pos")


def test_shared_above_is_detected_by_alias_and_by_copy(tmp_path: Path) -> None:
    other = [v + 0.1 for v in ABOVE_Q]
    aliased = (f"real_pos:\n- - [{ON_Q}, &above_a {ABOVE_Q}]\n  - [{ON_Q}, *above_a]\n  - [{ON_Q}, *above_a]\n"
               f"- - [{ON_Q}, {ABOVE_Q}]\n  - [{ON_Q}, {ABOVE_Q}]\n  - [{ON_Q}, {other}]\n")
    path = tmp_path / "t.yaml"
    path.write_text(aliased)
    rec = read_recorded_table(path, "real_pos")
    # tower 1 shares one above pose through a YAML alias, tower 2 copies it into heights 1 and 2 only.
    assert rec.shared_above == ((0, (0, 1, 2)), (1, (0, 1)))
    assert rec.shared_with(0, 2) == (0, 1, 2) and rec.shared_with(1, 2) == ()
    assert rec.missing == ()


def test_all_null_key_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "t.yaml"
    path.write_text("real_pos: [null, null]\n")
    with pytest.raises(TableError, match="field 'real_pos' holds no entry"):
        read_recorded_table(path, "real_pos")


def test_writing_a_key_keeps_a_partial_hand_recorded_key(lab_sim: Station, tmp_path: Path) -> None:
    hand = f"real_pos:\n- - [{ON_Q}]\n  - null\n- - [{ON_Q}, {ABOVE_Q}]\n  - [{ON_Q}, null]\n"
    out = tmp_path / "lab2_data.yaml"
    out.write_text(hand)
    write_table(out, generate_table(lab_sim), "sim_pos")
    assert hand in out.read_text()
    assert read_recorded_table(out, "real_pos").missing == ((0, 0, 1), (0, 1, 0), (0, 1, 1), (1, 1, 1))
