"""``ur3hanoi tables`` through the user's cache (ur3hanoi.labfile.generated): a hit writes the same bytes and prints
the same line as a miss, never a stale key, and fails on bad input exactly as a miss does.

Each test has a user cache of its own (XDG_CACHE_HOME under tmp_path). Whether a run was a hit is observed by making
the station loader fail during it: a hit never loads the station.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from ur3hanoi import cache
from ur3hanoi.cli import main
from ur3hanoi.labfile import read_table, table_sections, write_table
from ur3hanoi.labfile.generated import GENERATED_KEY, SOURCE_FOLDERS, generate_key
from ur3hanoi.station import load_station
from ur3hanoi.waypoints import generate_table

from .conftest import LAB_SIM, REPO

STUDENT = """\
# lab2_data.yaml of group 7 -- our own notes stay
home_pos: [0.0, -1.57, 1.57, -1.57, -1.57, 0.0]   # measured 2025-10-02

sim_pos: old   # to be regenerated
gripper:
  delay_s: 0.5      # tuned by hand
"""


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    xdg = tmp_path / "xdg"
    monkeypatch.setenv("XDG_CACHE_HOME", str(xdg))
    return xdg / "ur3hanoi"


def _entries(folder: Path) -> list[Path]:
    return sorted(folder.glob(f"{GENERATED_KEY}-*.cache"))


def _tables(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(["tables", *argv])
    out, err = capsys.readouterr()
    return code, out, err


def _no_station(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make loading a station fail: only a run that takes its key from the cache still succeeds."""
    def boom(path: object) -> None:
        raise AssertionError(f"the station {path} was loaded: not a cache hit")

    monkeypatch.setattr("ur3hanoi.station.load_station", boom)


@pytest.mark.parametrize(("station", "key", "convention", "student"), [
    ("lab_sim", "sim_pos", "controller", False),
    ("lab_real", "real_pos", "course", True),
    ("lab_sim", "real_pos", "course", True),
    ("lab_real", "sim_pos", "controller", False),
])
def test_a_hit_writes_the_bytes_and_prints_the_line_of_a_miss(station: str, key: str, convention: str, student: bool,
                                                              tmp_path: Path, private_cache: Path,
                                                              capsys: pytest.CaptureFixture[str],
                                                              monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    argv = (station, "--key", key, "--convention", convention, "-o", "lab2_data.yaml")
    before = STUDENT.encode() if student else None
    out = tmp_path / "lab2_data.yaml"
    if before is not None:
        out.write_bytes(before)
    miss = _tables(capsys, *argv)
    written = out.read_bytes()
    assert miss[0] == 0 and miss[2] == "" and len(_entries(private_cache)) == 1
    # The miss wrote what write_table writes (the library path, no cache involved).
    expected = tmp_path / "expected.yaml"
    if before is not None:
        expected.write_bytes(before)
    write_table(expected, generate_table(load_station(station)), key, calibration_label=station,
                convention=convention)
    assert written == expected.read_bytes()
    if before is not None:
        assert "# lab2_data.yaml of group 7" in written.decode() and "delay_s: 0.5      # tuned by hand" in \
            written.decode()
        out.write_bytes(before)
    else:
        out.unlink()
    with monkeypatch.context() as m:
        _no_station(m)
        hit = _tables(capsys, *argv)
    assert hit == miss
    assert out.read_bytes() == written
    for _ in range(2):  # again, on the file it wrote: nothing changes (the second time not even parsed)
        with monkeypatch.context() as m:
            _no_station(m)
            assert _tables(capsys, *argv) == miss
        assert out.read_bytes() == written


def test_the_hit_check_sees_a_miss(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                   monkeypatch: pytest.MonkeyPatch) -> None:
    """The observation the other tests rely on can fail: with nothing cached, the run loads the station."""
    _no_station(monkeypatch)
    with pytest.raises(AssertionError, match="not a cache hit"):
        main(["tables", "lab_sim", "--key", "sim_pos", "-o", str(tmp_path / "o.yaml"), "--debug"])


def test_a_changed_calibration_is_a_miss_and_gives_its_own_table(tmp_path: Path, private_cache: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    calibration = tmp_path / "station.yaml"
    calibration.write_text(LAB_SIM.read_text())
    out = tmp_path / "lab2_data.yaml"
    argv = (str(calibration), "--key", "sim_pos", "-o", str(out))
    assert _tables(capsys, *argv)[0] == 0
    first = read_table(out, "sim_pos")
    calibration.write_text(LAB_SIM.read_text().replace("origin: [0.40, 0.05, 0.0125]", "origin: [0.41, 0.05, 0.0125]"))
    assert _tables(capsys, *argv)[0] == 0
    assert len(_entries(private_cache)) == 2
    second = read_table(out, "sim_pos")
    fresh = generate_table(load_station(calibration)).q
    assert abs(second - fresh).max() <= 1e-9
    assert abs(second - first).max() > 1e-3  # a centimetre moves the joints by far more than the tolerance


def test_a_corrupt_or_foreign_entry_is_rebuilt(tmp_path: Path, private_cache: Path,
                                               capsys: pytest.CaptureFixture[str],
                                               monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "lab2_data.yaml"
    argv = ("lab_sim", "--key", "sim_pos", "-o", str(out))
    first = _tables(capsys, *argv)
    written = out.read_bytes()
    (entry,) = _entries(private_cache)
    good = entry.read_bytes()
    key = json.loads(good.splitlines()[0])["key"]
    mid = len(good) // 2
    for damage in (good[:-20], good[:mid] + bytes([good[mid] ^ 1]) + good[mid + 1:], b"", b"\x00" * 40):
        entry.write_bytes(damage)
        out.unlink()
        assert _tables(capsys, *argv) == first
        assert out.read_bytes() == written and entry.read_bytes() == good
    # An entry intact by its digest whose payload is not a generated key (another kind's, an older layout's).
    for payload in (b"[]", b'{"sections": 1}', json.dumps({**json.loads(cache.load(GENERATED_KEY, key) or b""),
                                                           "n_towers": "3"}).encode()):
        entry.unlink()
        assert cache.store(GENERATED_KEY, key, payload)
        out.unlink()
        assert _tables(capsys, *argv) == first
        assert out.read_bytes() == written and entry.read_bytes() == good
    with monkeypatch.context() as m:  # and the rebuilt entry is a hit
        _no_station(m)
        assert _tables(capsys, *argv) == first


def test_an_unwritable_cache_only_costs_the_rebuild(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("a file where the cache folder would be\n")
    monkeypatch.setenv("XDG_CACHE_HOME", str(blocker))
    out = tmp_path / "lab2_data.yaml"
    argv = ("lab_real", "--key", "real_pos", "-o", str(out))
    runs = [_tables(capsys, *argv) for _ in range(2)]
    assert runs[0] == runs[1] and runs[0][0] == 0 and runs[0][2] == ""
    assert abs(read_table(out, "real_pos") - generate_table(load_station("lab_real")).q).max() <= 1e-9
    assert blocker.read_text() == "a file where the cache folder would be\n"


BAD_VALUE = ("size: 0.0318", "size: -0.0318")


@pytest.mark.parametrize("case", ["bad-calibration", "not-a-mapping", "not-yaml", "bad-key-entry"])
def test_bad_input_fails_alike_with_the_cache_warm_or_cold(case: str, tmp_path: Path,
                                                           capsys: pytest.CaptureFixture[str],
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    calibration = tmp_path / "station.yaml"
    calibration.write_text(LAB_SIM.read_text())
    out = tmp_path / "lab2_data.yaml"
    argv = (str(calibration), "--key", "sim_pos", "-o", str(out))
    assert _tables(capsys, *argv)[0] == 0  # the cache now holds the valid calibration's key
    assert _tables(capsys, *argv)[0] == 0  # and that the file holds it (ur3hanoi.labfile.unchanged)
    good = out.read_bytes()
    if case == "bad-calibration":
        calibration.write_text(LAB_SIM.read_text().replace(*BAD_VALUE))
    elif case == "not-a-mapping":
        out.write_text("- 1\n- 2\n")
    elif case == "not-yaml":
        out.write_text("sim_pos: [unclosed\n")
    else:  # a key given twice: strict YAML refuses it
        out.write_bytes(good + b"sim_pos: []\n")
    before = out.read_bytes()
    warm = _tables(capsys, *argv)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cold"))
    cold = _tables(capsys, *argv)
    assert warm == cold
    code, stdout, stderr = warm
    assert code != 0 and stdout == "" and stderr.count("\n") == 1 and "Traceback" not in stderr
    assert stderr.startswith("ur3hanoi: error: ")
    expected = {"bad-calibration": "blocks.size", "not-a-mapping": "not a mapping", "not-yaml": "not valid YAML",
                "bad-key-entry": "duplicate key 'sim_pos'"}[case]
    assert expected in stderr
    assert out.read_bytes() == before
    assert sorted({p.name for p in tmp_path.iterdir()} - {"cold", "xdg"}) == ["lab2_data.yaml", "station.yaml"]
    if case == "bad-calibration":  # an invalid calibration is never kept
        assert _entries(tmp_path / "cold" / "ur3hanoi") == []


def test_generate_key_is_what_write_table_writes(tmp_path: Path) -> None:
    """The library function: its sections are table_sections' (the miss) and again from the entry (the hit)."""
    table = generate_table(load_station("lab_real"))
    want = table_sections(table, "real_pos", "lab_real", "course")
    for _ in range(2):
        got = generate_key("lab_real", "real_pos", "pinocchio", "course", label="lab_real")
        assert got.sections == want
        assert (got.n_towers, got.n_heights, got.n_poses) == (table.q.shape[0], table.q.shape[1], len(table.results))
        assert got.max_position_error == table.max_position_error
    assert len(_entries(cache.cache_dir())) == 1


_PROBE = """
import contextlib, io, json, sys
import ur3hanoi.cli
with contextlib.redirect_stdout(io.StringIO()):
    code = ur3hanoi.cli.main({argv!r})
files = sorted(m.__file__ for name, m in list(sys.modules.items())
               if name.split(".")[0] == "ur3hanoi" and getattr(m, "__file__", None))
print(json.dumps([code, files]))
"""


def test_the_key_covers_every_module_a_run_imports(tmp_path: Path) -> None:
    """A cold run (nothing cached: the station, the IK, the formatting) imports no ur3hanoi module outside
    SOURCE_FOLDERS, whose source is in the key."""
    import os

    argv = ["tables", "lab_sim", "--key", "sim_pos", "-o", str(tmp_path / "o.yaml")]
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp_path / "xdg")}
    proc = subprocess.run([sys.executable, "-c", _PROBE.format(argv=argv)], capture_output=True, text=True, cwd=REPO,
                          timeout=120, env=env)
    assert proc.returncode == 0, proc.stderr
    code, files = json.loads(proc.stdout)
    assert code == 0
    modules = {Path(f).resolve().relative_to(REPO / "ur3hanoi") for f in files}
    assert {Path("ik.py"), Path("station.py"), Path("labfile/write.py")} <= modules  # it was a cold run
    folders = {"" if len(m.parts) == 1 else m.parts[0] for m in modules}
    assert folders <= set(SOURCE_FOLDERS), sorted(str(m) for m in modules)


def test_a_calibration_changed_while_it_is_read_is_not_kept(tmp_path: Path, private_cache: Path,
                                                            monkeypatch: pytest.MonkeyPatch) -> None:
    """The key's inputs hold the bytes read first; a station loaded from other bytes (the file edited meanwhile)
    gives its own key to this run but no entry under the first bytes' key."""
    calibration = tmp_path / "station.yaml"
    calibration.write_text(LAB_SIM.read_text())
    moved = LAB_SIM.read_text().replace("origin: [0.40, 0.05, 0.0125]", "origin: [0.41, 0.05, 0.0125]")

    def edited_meanwhile(path: object) -> object:
        calibration.write_text(moved)
        return load_station(path)  # type: ignore[arg-type]

    with monkeypatch.context() as m:
        m.setattr("ur3hanoi.station.load_station", edited_meanwhile)
        got = generate_key(str(calibration), "sim_pos")
    assert _entries(private_cache) == []
    fresh = generate_key(str(calibration), "sim_pos")  # now a miss on the new bytes, kept
    assert got.sections == fresh.sections and len(_entries(private_cache)) == 1
