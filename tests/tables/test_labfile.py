"""lab2_data.yaml: the course format, strict reading, in-place updates that keep other keys, atomicity, locking."""

from __future__ import annotations

import multiprocessing
import os
import re
import shutil
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from tests.conftest import LAB_REAL, LAB_SIM, REPO
from ur3hanoi.cli import main
from ur3hanoi.errors import OutputError, TableError, printable
from ur3hanoi.robot.ik_solvers import pose_errors
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import T_world_tcp
from ur3hanoi.tables import (
    ANGLE_DECIMALS,
    FILE_HEADER,
    format_number,
    format_q,
    parse_q,
    read_lab_file,
    read_recorded_table,
    read_table,
    splice_yaml,
    write_table,
)
from ur3hanoi.tables.ik_table import generate_table

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


_NUMBER = re.compile(r"-?\d+\.\d+")
ANGLE_TOL = 1e-9  # [rad] and [m]: the IK's own accuracy; last-bit noise between CPUs is about 1e-15


def assert_same_tables(text: str, expected: str) -> None:
    """Two lab files hold the same tables: numbers within ANGLE_TOL, everything else (keys, comments, layout,
    provenance) the same text."""
    assert _NUMBER.sub("#", text) == _NUMBER.sub("#", expected)
    got, want = yaml.safe_load(text), yaml.safe_load(expected)
    assert got.keys() == want.keys()
    for key in want:
        np.testing.assert_allclose(np.array(got[key], dtype=float), np.array(want[key], dtype=float),
                                   rtol=0.0, atol=ANGLE_TOL, err_msg=f"{key}: run `make tables`")


def test_shipped_table_is_not_stale(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(REPO)
    fresh = tmp_path / "lab2_data.yaml"
    _regenerate(fresh)
    assert_same_tables(fresh.read_text(), (REPO / "tables/lab2_data.yaml").read_text())


def test_last_bit_noise_does_not_show_in_the_file(lab_sim: Station) -> None:
    # Another CPU computes the same IK up to a few ulps (1.8e-15 rad seen between two machines): the file's text
    # must not change. Seeded angles, so no value sits on a rounding boundary by chance on any machine.
    rng = np.random.default_rng(17)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, size=(3, 3, 2, 6))
    text = format_q(q, "sim_pos")
    for ulps in (1, 4, -4):
        noisy = q.copy()
        for _ in range(abs(ulps)):
            noisy = np.nextafter(noisy, np.inf if ulps > 0 else -np.inf)
        assert format_q(noisy, "sim_pos") == text
    back = np.array(yaml.safe_load(text)["sim_pos"], dtype=float)
    np.testing.assert_allclose(back, q, rtol=0.0, atol=0.5 * 10.0 ** -ANGLE_DECIMALS)
    assert format_number(-1e-17) == "0.0" and format_number(2.0) == "2.0" and format_number(-0.5) == "-0.5"
    assert all(isinstance(yaml.safe_load(format_number(x)), float) for x in (0.0, -0.0, 1e-12, 3.0, -6.2831853))


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
         r"key 'sim_pos' not found \(table keys present: none\); is 'sim_pso' a misspelling of it\?"),
        ("- 1\n", r"lab2_data.yaml: the top level is a list, not a mapping of keys \(sim_pos, real_pos, block_xy_pos, "
                  r"or your own\)"),
        ("sim_pos: [[[[0.2, .inf, 0, 0, 0, 0]]]]\n", r"field 'sim_pos\[0\]\[0\]\[0\]\[1\]' = inf is invalid"),
        ("sim_pos: old\n", r"field 'sim_pos' = 'old' is invalid: expected a list of 1..10 towers"),
    ],
    ids=["duplicate", "typo", "not-a-mapping", "inf", "junk"],
)
def test_strict_lab_file(tmp_path: Path, text: str, match: str) -> None:
    path = tmp_path / "lab2_data.yaml"
    path.write_text(text)
    with pytest.raises(TableError, match=match) as info:
        read_recorded_table(path, "sim_pos")
    assert "\n" not in str(info.value)


def test_readers_check_only_the_key_they_read(tmp_path: Path) -> None:
    # A student's own keys, junk in real_pos and a malformed block_xy_pos do not stop anyone reading sim_pos.
    path = tmp_path / "lab2_data.yaml"
    path.write_text(f"home_pos: [1, 2, 3]\nextra_notes: {{station: 4, ok: yes}}\nreal_pos: old\n"
                    f"block_xy_pos: [[1]]\nsim_pos:\n- - [{ON_Q}, {ABOVE_Q}]\n")
    np.testing.assert_array_equal(read_table(path, "sim_pos"), [[[ON_Q, ABOVE_Q]]])
    with pytest.raises(TableError, match=r"field 'real_pos' = 'old' is invalid"):
        read_table(path, "real_pos")


STUDENT_FILE = """\
# Lab 2, group 7: our own notes stay ours
home_pos: &home [2.0944, -1.5708, 1.5708, -1.5708, -1.5708, 0.0]   # radians(120, -90, 90, -90, -90, 0)
station:   # YAML 1.1 reads these as 8, True and 90: kept as the student wrote them
  door: 010
  lights: on
  slot: 1:30

sim_pos: old   # to be regenerated
# notes about the station
extra_notes: |
  suction cup replaced on 2025-10-02
  keep: the text exactly
real_pos: [[1, 2]]   # malformed, but not ours to touch
park_pos: *home
"""


@pytest.mark.parametrize(
    ("text", "old_entry"),
    [
        (STUDENT_FILE, "sim_pos: old   # to be regenerated\n"),
        (STUDENT_FILE.replace("sim_pos: old   # to be regenerated\n", ""), ""),
        ("home_pos: 1", ""),
        ("\ufeff# a BOM and CRLF line ends\r\nsim_pos:\r\n- 1\r\nb: 2\r\n", "sim_pos:\r\n- 1\r\n"),
        ("---\nsim_pos:\n  - [junk]\n  # an indented comment about the junk\n# next key\nhome: 1\n...\n",
         "sim_pos:\n  - [junk]\n"),  # comments after the value's last line belong to what follows
        ("  sim_pos: 1\n  other: 2\n", "  sim_pos: 1\n"),
        ("{home_pos: 1, sim_pos: old}\n", "sim_pos: old"),
        ("a: 1\n? sim_pos\n: old\nb: 2\n", "? sim_pos\n: old\n"),
    ],
    ids=["student", "no-key-yet", "no-newline", "bom-crlf", "markers", "indented", "flow", "explicit-key"],
)
def test_writing_a_key_keeps_every_other_byte(lab_real: Station, tmp_path: Path, text: str, old_entry: str) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_bytes(text.encode("utf-8"))
    before = yaml.safe_load(text.lstrip("\ufeff"))
    table = generate_table(lab_real)
    write_table(out, table, "sim_pos")
    raw = out.read_bytes()
    new = raw.decode("utf-8")
    assert raw.startswith(b"\xef\xbb\xbf") == text.startswith("\ufeff")
    # The new entry (its provenance line and the generated block) is one contiguous piece, where the old one was
    # or after the last key; taking it out leaves the old file without its old entry, byte for byte.
    if "{" in text:
        ours = "sim_pos: " + re.search(r"\[\[\[\[.*?\]\]\]\]", new).group(0)  # type: ignore[union-attr]
    else:
        nl = "\r\n" if "\r\n" in text else "\n"
        indent = text[:len(text) - len(text.lstrip(" "))]
        start = new.index(f"{indent}# ur3hanoi ")
        end = new.index("# tower 3 height 3 above", start) + len("# tower 3 height 3 above") + len(nl)
        ours = new[start:end]
        block = "".join(indent + line + nl for line in format_q(table.q, "sim_pos").splitlines())
        assert ours.endswith(block) and ours.count(nl) == block.count(nl) + 1
    rest = new.replace(ours, "", 1)
    missing_nl = "" if text.endswith("\n") or text.endswith("}\n") else "\n"
    assert rest == (text.replace(old_entry, "", 1) if old_entry else text + missing_nl)
    data = yaml.safe_load(new.lstrip("\ufeff"))
    np.testing.assert_allclose(np.array(data["sim_pos"], dtype=float), table.q, rtol=0.0, atol=1e-9)
    assert {k: v for k, v in data.items() if k != "sim_pos"} == {k: v for k, v in (before or {}).items()
                                                                 if k != "sim_pos"}
    # Writing it again changes nothing.
    write_table(out, table, "sim_pos")
    assert out.read_bytes() == raw


@pytest.mark.parametrize("text", ["- 1\n- 2\n", "just a line of text\n", "42\n", "a: [unclosed\n"])
def test_a_file_that_is_not_a_mapping_is_refused_untouched(lab_real: Station, tmp_path: Path, text: str) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text(text)
    with pytest.raises(TableError, match=r"lab2_data.yaml: (the top level is an? \w+, not a mapping|not valid YAML)"
                       ) as info:
        write_table(out, generate_table(lab_real), "real_pos")
    assert "\n" not in str(info.value)
    assert out.read_text() == text and _listing(tmp_path) == ["lab2_data.yaml"]


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
    np.testing.assert_allclose(read_table(out, "real_pos"), generate_table(lab_real).q, rtol=0.0, atol=ANGLE_TOL)
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
    np.testing.assert_allclose(read_table(target, "real_pos"), generate_table(lab_real).q, rtol=0.0,
                               atol=ANGLE_TOL)
    assert sorted(p.name for p in target.parent.iterdir()) == ["lab2_data.yaml"]


def test_output_that_is_the_calibration_is_refused(tmp_path: Path) -> None:
    cal = tmp_path / "station.yaml"
    shutil.copy(LAB_REAL, cal)
    before = cal.read_bytes()
    from ur3hanoi.station.calibration import load_station

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


# ------------------------------------------------------------------------------ splicing into any student file

_VALUES = [" 1", " old", " [1, 2]", " {a: yes, b: [x]}", "\n- 1\n- [2, 3]", "\n  - 1\n  - 2", " |\n  text\n  more",
           "", " 'quoted: # not a comment'", " &a{i} [1.5]", "\n  nested: 1\n  deeper:\n    - x"]
_FILLER = ["", "\n", "# a comment\n", "\n# about the next key\n", "   # indented comment\n"]
_SPLICE_Q = np.arange(2 * 2 * 2 * 6, dtype=float).reshape(2, 2, 2, 6) / 7.0


@settings(max_examples=100, deadline=None, derandomize=True)
@given(keys=st.lists(st.sampled_from(["home_pos", "extra_notes", "real_pos", "notes", "sim_pos", "block_xy_pos"]),
                     unique=True, max_size=5),
       values=st.lists(st.sampled_from(_VALUES), min_size=5, max_size=5),
       fillers=st.lists(st.sampled_from(_FILLER), min_size=6, max_size=6),
       comments=st.lists(st.booleans(), min_size=5, max_size=5))
def test_splice_keeps_every_byte_outside_the_key(keys: list[str], values: list[str], fillers: list[str],
                                                 comments: list[bool]) -> None:
    parts, old_entry = [fillers[5]], None
    for i, key in enumerate(keys):
        value = values[i].replace("{i}", str(i))
        comment = "  # my comment" if comments[i] and "\n" not in value and "|" not in value else ""
        entry = f"{key}:{value}{comment}\n"
        if key == "sim_pos":
            old_entry = len(parts)
        parts += [entry, fillers[i]]
    old = "".join(parts)
    before = yaml.safe_load(old) or {}
    block = format_q(_SPLICE_Q, "sim_pos")
    header = "# ur3hanoi 0.0: sim_pos generated from test"
    new = splice_yaml(old, {"sim_pos": block}, {"sim_pos": header})
    ours = header + "\n" + block
    assert new.count(ours) == 1
    expected = "".join(parts[:old_entry] + parts[old_entry + 1:]) if old_entry is not None else old
    rest = new.replace(ours, "", 1)
    if not keys:
        rest = rest.replace(FILE_HEADER, "", 1) if not old.strip() else rest
    assert rest == expected
    after = yaml.safe_load(new)
    np.testing.assert_allclose(np.array(after["sim_pos"], dtype=float), _SPLICE_Q, rtol=0.0, atol=1e-10)
    assert {k: v for k, v in after.items() if k != "sim_pos"} == {k: v for k, v in before.items() if k != "sim_pos"}


def test_a_key_whose_anchor_another_key_uses_is_not_replaced(lab_real: Station, tmp_path: Path) -> None:
    # Replacing sim_pos would leave `backup: *q` pointing nowhere: refused in one line, the file untouched.
    out = tmp_path / "lab2_data.yaml"
    out.write_text("sim_pos: &q [1]\nbackup: *q\n")
    with pytest.raises(TableError, match=r"lab2_data.yaml: cannot write 'sim_pos' in place \(not valid YAML: found "
                                         r"undefined alias 'q' .*\); file left unchanged$"):
        write_table(out, generate_table(lab_real), "sim_pos")
    assert out.read_text() == "sim_pos: &q [1]\nbackup: *q\n"


def test_for_solve_needs_the_visited_entries_only(tmp_path: Path) -> None:
    # 3 towers x 2 heights; one block from tower 1 to 3 visits height 1 of towers 1 and 3 only.
    full = f"- - [{ON_Q}, {ABOVE_Q}]\n  - [{ON_Q}, {ABOVE_Q}]\n"
    path = tmp_path / "t.yaml"
    path.write_text(f"real_pos:\n- - [{ON_Q}, {ABOVE_Q}]\n  - null\n- null\n{full}")
    rec = read_recorded_table(path, "real_pos")
    q = rec.for_solve(0, 2, 1)
    np.testing.assert_array_equal(q[2, 0, 1], ABOVE_Q)
    with pytest.raises(TableError, match=r"t.yaml:real_pos: 4 table entries the solve needs are missing: tower 1 "
                                         r"height 2 on \(Q\[0\]\[1\]\[0\]\); tower 1 height 2 above .*; tower 2 "
                                         r"height 1 above \(Q\[1\]\[0\]\[1\]\)$"):
        rec.for_solve(0, 2, 2)


def test_every_public_name_resolves_from_its_module() -> None:
    """The package imports its modules on first use (ur3hanoi.tables.__getattr__): every name of __all__ is there,
    and an unknown one is an AttributeError."""
    import ur3hanoi.tables as labfile

    for name in labfile.__all__:
        assert getattr(labfile, name) is not None, name
    assert set(labfile.__all__) <= set(dir(labfile))
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        labfile.nope  # noqa: B018


@pytest.mark.parametrize(("key", "named"), [("s\u200bim_pos", "U+200B ZERO WIDTH SPACE"),
                                            ("\u0455im_pos", "U+0455 CYRILLIC SMALL LETTER DZE"),
                                            ("real_\u00adpos", "U+00AD SOFT HYPHEN"),
                                            ("\uff53im_pos", "U+FF53 FULLWIDTH LATIN SMALL LETTER S")])
def test_a_key_that_looks_like_a_known_one_is_warned_about_where_it_is_written_and_read(
        key: str, named: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The student sees two keys that look alike and does not know why: every write and read that meets the
    look-alike next to the key it imitates says so, naming the character; the file is written as before."""
    known = "real_pos" if key.startswith("real") else "sim_pos"
    cal = "lab_real" if known == "real_pos" else "lab_sim"
    path = tmp_path / "lab2_data.yaml"
    path.write_text(f"{key}: [mine]\n", encoding="utf-8")
    for _ in range(2):  # the second run writes the same bytes back: the warning comes again
        assert main(["tables", cal, "--key", known, "-o", str(path)]) == 0
        err = capsys.readouterr().err
        assert err.splitlines() == [f"ur3hanoi: warning: {path}: key '{printable(key)}' looks like '{known}' but is "
                                    f"another key (it has {named}): ur3hanoi reads and writes '{known}' only; rename "
                                    "or delete the look-alike"], err
    data = yaml.safe_load(path.read_text(encoding="utf-8"))
    assert data[key] == ["mine"] and known in data
    assert main(["check-table", str(path), "--key", known, "--calibration", cal]) == 0
    assert f"looks like '{known}'" in capsys.readouterr().err
    plain = tmp_path / "plain.yaml"
    plain.write_text("sim_pos_mine: 1\nreal: 2\n")
    assert main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(plain)]) == 0
    assert "warning" not in capsys.readouterr().err
