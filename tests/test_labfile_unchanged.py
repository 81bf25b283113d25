"""Lab files known to hold their keys already (ur3hanoi.labfile.unchanged): written again without a parse, with
the bytes a full read, splice and check writes, and only for the very bytes and keys that were checked.

Whether a write parsed the file is observed by making the parse fail during it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from ur3hanoi.errors import TableError
from ur3hanoi.labfile import Sections, table_sections, write_sections
from ur3hanoi.labfile.unchanged import UNCHANGED
from ur3hanoi.station import Station
from ur3hanoi.waypoints import generate_table

STUDENT = "\ufeff# group 7\r\nhome_pos: [0.0, -1.57]   # ours\r\nsim_pos: old\r\nnotes: {a: 1}\r\n"


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    xdg = tmp_path / "xdg"
    monkeypatch.setenv("XDG_CACHE_HOME", str(xdg))
    return xdg / "ur3hanoi"


@pytest.fixture(scope="module")
def sections(lab_sim: Station) -> Sections:
    return table_sections(generate_table(lab_sim), "sim_pos", "lab_sim")


def _no_parse(monkeypatch: pytest.MonkeyPatch) -> None:
    def boom(raw: bytes, source: str) -> None:
        raise AssertionError(f"{source} was parsed")

    monkeypatch.setattr("ur3hanoi.labfile.update.parse_lab_file", boom)


def _entries(folder: Path) -> list[Path]:
    return sorted(folder.glob(f"{UNCHANGED}-*.cache"))


def test_a_file_holding_its_keys_is_written_back_unparsed(sections: Sections, tmp_path: Path, private_cache: Path,
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_bytes(STUDENT.encode())
    text = write_sections(out, sections)  # the student's file changes: nothing to remember
    written = out.read_bytes()
    assert written.startswith(b"\xef\xbb\xbf# group 7\r\n") and b"notes: {a: 1}\r\n" in written
    assert _entries(private_cache) == []
    assert write_sections(out, sections) == text  # parsed in full: the file holds its keys
    assert out.read_bytes() == written and len(_entries(private_cache)) == 1
    inode = out.stat().st_ino
    with monkeypatch.context() as m:
        _no_parse(m)
        assert write_sections(out, sections) == text
    assert out.read_bytes() == written
    assert out.stat().st_ino != inode  # written again (atomically replaced), as the full path does


def test_the_parse_check_can_fail(sections: Sections, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_bytes(STUDENT.encode())
    _no_parse(monkeypatch)
    with pytest.raises(AssertionError, match="was parsed"):
        write_sections(out, sections)


@pytest.mark.parametrize("edit", ["digit", "comment", "not-a-mapping", "duplicate-key"])
def test_other_bytes_are_read_and_checked_in_full(edit: str, sections: Sections, tmp_path: Path,
                                                  private_cache: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    write_sections(out, sections)
    written = write_sections(out, sections)
    assert len(_entries(private_cache)) == 1  # remembered
    if edit == "digit":  # one angle changed in its last decimal: regenerated
        i = written.index("- [") + 4
        out.write_text(written[:i] + ("1" if written[i] != "1" else "2") + written[i + 1:])
        assert write_sections(out, sections) == written
    elif edit == "comment":  # a comment of the student's own: kept
        out.write_text(written + "# checked by the TA\n")
        assert write_sections(out, sections) == written + "# checked by the TA\n"
    else:
        bad = "- 1\n- 2\n" if edit == "not-a-mapping" else written + "sim_pos: []\n"
        out.write_text(bad)
        match = "not a mapping" if edit == "not-a-mapping" else "duplicate key 'sim_pos'"
        with pytest.raises(TableError, match=match) as info:
            write_sections(out, sections)
        assert "\n" not in str(info.value) and out.read_text() == bad
    assert sorted(p.name for p in tmp_path.iterdir()) == ["lab2_data.yaml", "xdg"]


def test_other_keys_into_the_same_bytes_are_not_a_hit(lab_sim: Station, sections: Sections, tmp_path: Path,
                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    write_sections(out, sections)
    write_sections(out, sections)  # remembered
    course = table_sections(generate_table(lab_sim), "sim_pos", "lab_sim", "course")
    fresh = tmp_path / "fresh.yaml"
    write_sections(fresh, course)
    with monkeypatch.context() as m:
        _no_parse(m)
        with pytest.raises(AssertionError, match="was parsed"):
            write_sections(out, course)
    assert write_sections(out, course) == fresh.read_text()


def test_a_corrupt_entry_is_no_entry(sections: Sections, tmp_path: Path, private_cache: Path,
                                     monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    write_sections(out, sections)
    written = write_sections(out, sections)
    (entry,) = _entries(private_cache)
    entry.write_bytes(entry.read_bytes()[:-3])
    with monkeypatch.context() as m:
        _no_parse(m)
        with pytest.raises(AssertionError, match="was parsed"):
            write_sections(out, sections)
    assert write_sections(out, sections) == written and out.read_text() == written
