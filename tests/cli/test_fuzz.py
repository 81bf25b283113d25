"""Fuzzing every loader and every command with mutated and hostile inputs (hypothesis, derandomized).

Each example mutates one of the shipped files (a station, the taught-points example, the lab table) or picks a
hostile input (alias bomb, deep nesting, huge integer, UTF-16, /dev/zero, a FIFO, a directory, 2 MiB), then runs
the loaders and the commands that read it, in-process through ``ur3hanoi.cli.main``, and checks:

- never a traceback and never an internal error: the exit code is 0, 1 (``check-table`` over tolerance) or 2, and
  a failing run prints exactly one line on stderr;
- every file that existed before a failing run is byte-identical after it, and no file appeared;
- a successful run leaves a valid output (the lab table, the calibration, the CSV reload);
- no hang: every run is interrupted after :data:`RUN_TIMEOUT_S` (and a few run as subprocesses with a timeout).

Bad inputs fail before any planning or simulation, so the whole file stays well under a minute.
"""

from __future__ import annotations

import contextlib
import io
import json
import math
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import pytest
import yaml
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from tests.conftest import LAB_REAL, LAB_SIM, REPO
from ur3hanoi.calibrate.taught import load_taught
from ur3hanoi.cli import main
from ur3hanoi.errors import InputError
from ur3hanoi.io.resources import TAUGHT_EXAMPLE, stations_dir
from ur3hanoi.station.calibration import load_station
from ur3hanoi.tables import read_lab_file

LAB_TABLE = REPO / "tables/lab2_data.yaml"
TAUGHT = stations_dir() / TAUGHT_EXAMPLE
SHIPPED = {"lab_sim": LAB_SIM, "lab_real": LAB_REAL, "taught": TAUGHT, "table": LAB_TABLE}
RUN_TIMEOUT_S = 20
FUZZ = settings(derandomize=True, deadline=None, database=None, print_blob=True,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


# ----------------------------------------------------------------------------------------------- mutations


def _laughs(levels: int) -> str:
    lines = ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]" for i in range(1, levels + 1)]
    return "\n".join(lines) + "\n"


HOSTILE_TEXTS: list[bytes] = [
    _laughs(9).encode(),
    b"a: &a [1, *a]\n",
    b"[" * 50_000 + b"]" * 50_000,
    b"".join(b" " * i + b"k%d:\n" % i for i in range(100)),
    b"grid: {towers: " + b"9" * 400 + b"}\n",
    b"name: " + b"9" * 5000 + b"\n",
    "units: deg\n".encode("utf-16"),
    "layout: caf\xe9\n".encode("latin-1"),
    b"\xff\xfe\x00\x00",
    b"\x00" * 64,
    b"!!python/object/apply:os.system ['echo pwned']\n",
    b"a: 1\n---\nb: 2\n",
    b"x: 2025-13-45\n",
    b"? [1, 2]\n: 3\n",
    b"- " * 5000 + b"x\n",
    b"",
    b"~\n",
    b"[]\n",
    b"'just a string'\n",
    b"{" + b", ".join(b"k%d: %d" % (i, i) for i in range(30_000)) + b"}\n",
]
HOSTILE_PATHS = ["fifo", "dev-zero", "directory", "missing", "too-large", "symlink-loop", "symlink-to-dev-zero"]

ODD_VALUES: list[Any] = [math.nan, math.inf, -math.inf, 10**400, -(10**400), True, False, None, "", "x" * 2000,
                         [], {}, [[]], 0, -1, 1e308, -1e-320, "0.5", "\x1b[2J\n", [math.nan] * 6, [0] * 7,
                         {"a": 1}, [[0.0] * 6] * 2, 2**63, -0.0, "ninety", [1, "2", 3]]
VALUES = st.one_of(st.sampled_from(ODD_VALUES), st.floats(allow_nan=True, allow_infinity=True),
                   st.integers(-10**6, 10**6), st.text(max_size=12),
                   st.lists(st.floats(-10, 10, allow_nan=False), max_size=8))


def _paths(node: Any, prefix: tuple[Any, ...] = ()) -> Iterator[tuple[Any, ...]]:
    yield prefix
    if isinstance(node, dict):
        for k, v in node.items():
            yield from _paths(v, (*prefix, k))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from _paths(v, (*prefix, i))


def _typo(key: str, choice: int) -> str:
    variants = [key[:-1], key + "s", key[1:] + key[0], key.upper(), key + "_deg", key.replace("_deg", ""),
                key.replace("_", ""), key[:1] + key[2:1:-1] + key[1:2] + key[3:], f"{key} "]
    return variants[choice % len(variants)] or "x"


@st.composite
def tree_mutation(draw: st.DrawFn, text: str) -> bytes:
    """Parse the shipped file, change one node (delete, rename, replace, wrap), dump it back."""
    data = yaml.safe_load(text)
    paths = list(_paths(data))[1:]
    path = draw(st.sampled_from(paths))
    *parents, last = path
    node = data
    for p in parents:
        node = node[p]
    op = draw(st.sampled_from(["delete", "rename", "replace", "replace", "wrap", "add"]))
    if op == "delete":
        del node[last]
    elif op == "rename" and isinstance(node, dict):
        node[_typo(str(last), draw(st.integers(0, 100)))] = node.pop(last)
    elif op == "wrap":
        node[last] = [node[last]]
    elif op == "add" and isinstance(node, dict):
        node[draw(st.sampled_from(["extra", "base_rpy", "yaw", "points", "sim_pos", "notes", "q"]))] = 1
    else:
        node[last] = draw(VALUES)
    return yaml.safe_dump(data, sort_keys=False, allow_unicode=draw(st.booleans())).encode("utf-8")


@st.composite
def text_mutation(draw: st.DrawFn, text: str) -> bytes:
    """Change the raw bytes: duplicate or drop a line, splice in bytes, truncate, re-encode."""
    raw = text.encode()
    lines = raw.splitlines(keepends=True)
    op = draw(st.sampled_from(["dup-line", "drop-line", "insert", "replace", "truncate", "utf16", "bom", "tab"]))
    i = draw(st.integers(0, len(lines) - 1))
    if op == "dup-line":
        return b"".join(lines[: i + 1] + lines[i:])
    if op == "drop-line":
        return b"".join(lines[:i] + lines[i + 1:])
    pos = draw(st.integers(0, len(raw)))
    if op == "insert":
        return raw[:pos] + draw(st.binary(min_size=1, max_size=6)) + raw[pos:]
    if op == "replace":
        return raw[:pos] + draw(st.sampled_from([b":", b"-", b"[", b"{", b"&a", b"*a", b"'", b"\\", b"#", b"e9"]))
    if op == "truncate":
        return raw[:pos]
    if op == "utf16":
        return text.encode("utf-16")
    if op == "bom":
        return b"\xef\xbb\xbf" + raw
    return raw[:pos] + b"\t" + raw[pos:]


@st.composite
def style_mutation(draw: st.DrawFn, text: str) -> bytes:
    """The same data in another valid YAML style (flow, canonical, JSON-like, other indents, `---`)."""
    data = yaml.safe_load(text)
    style = draw(st.sampled_from(["flow", "canonical", "indent", "start", "json"]))
    if style == "json":
        return json.dumps(data).encode()
    return yaml.safe_dump(data, default_flow_style=True if style == "flow" else None, canonical=style == "canonical",
                          indent=draw(st.integers(2, 6)), explicit_start=style == "start").encode()


def input_file(name: str) -> st.SearchStrategy[bytes | str]:
    """A mutated copy of the shipped file ``name`` (in another style or not), a hostile text, or a hostile path."""
    text = SHIPPED[name].read_text()
    return st.one_of(tree_mutation(text), tree_mutation(text), text_mutation(text), style_mutation(text),
                     st.sampled_from(HOSTILE_TEXTS), st.sampled_from(HOSTILE_PATHS))


# ------------------------------------------------------------------------------------------------ running


class Hang(BaseException):
    """A run took longer than RUN_TIMEOUT_S (a BaseException, so `main` cannot turn it into an exit code)."""


def _alarm(signum: int, frame: Any) -> None:
    raise Hang


@contextlib.contextmanager
def _work_dir() -> Iterator[Path]:
    with tempfile.TemporaryDirectory(prefix="ur3hanoi-fuzz-") as d:
        yield Path(d)


def _place(work: Path, name: str, content: bytes | str) -> str:
    """Put the input at ``work/name`` (a file, or a FIFO, device link, directory...) and return its path."""
    path = work / name
    if isinstance(content, bytes):
        path.write_bytes(content)
    elif content == "fifo":
        os.mkfifo(path)
    elif content == "dev-zero":
        return "/dev/zero"
    elif content == "directory":
        path.mkdir()
    elif content == "too-large":
        path.write_bytes(b"# padding\n" * 210_000)
    elif content == "symlink-loop":
        path.symlink_to(path)
    elif content == "symlink-to-dev-zero":
        path.symlink_to("/dev/zero")
    return str(path)


def _snapshot(work: Path) -> dict[str, bytes | None]:
    snap: dict[str, bytes | None] = {}
    for p in sorted(work.rglob("*")):
        regular = p.is_file() and not p.is_symlink()
        snap[str(p.relative_to(work))] = p.read_bytes() if regular else None
    return snap


def run(argv: Sequence[str]) -> tuple[int, str, str]:
    """``main(argv)`` in-process with captured output and a timeout."""
    out, err = io.StringIO(), io.StringIO()
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(RUN_TIMEOUT_S)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            rc = main(list(argv))
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return rc, out.getvalue(), err.getvalue()


def check_run(work: Path, argv: Sequence[str], allowed: Sequence[int] = (0, 2)) -> int:
    """Run a command and check the contract; returns its exit code."""
    before = _snapshot(work)
    rc, _, err = run(argv)
    event(f"{argv[0]} exit {rc}")
    assert "Traceback" not in err, (argv, err)
    assert rc in allowed, (argv, rc, err)
    if rc in (2, 3):  # bad input, or (solve) a suction fault the simulated run halted on: one line each
        lines = err.splitlines()
        assert len(lines) == 1 and lines[0].startswith("ur3hanoi") and ": error: " in lines[0], (argv, err)
        assert len(lines[0]) < 1200, (argv, err)
        assert _snapshot(work) == before, (argv, err)
    else:
        assert all(line.startswith("ur3hanoi: warning: ") for line in err.splitlines()), (argv, err)
    return rc


def check_loader(load: Any, path: str) -> bool:
    """The loader returns, or raises an InputError: nothing else. True if it loaded."""
    old = signal.signal(signal.SIGALRM, _alarm)
    signal.alarm(RUN_TIMEOUT_S)
    try:
        load(path)
    except InputError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 1200, str(exc)
        return False
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    return True


def _existing_outputs(work: Path) -> tuple[Path, Path, Path]:
    table = work / "lab2_data.yaml"
    shutil.copy(LAB_TABLE, table)
    cal = work / "previous_station.yaml"
    cal.write_text("# an earlier calibration: must survive any failing run\n")
    csv = work / "traj.csv"
    csv.write_text("t,q1\n")
    return table, cal, csv


# -------------------------------------------------------------------------------------------------- tests


@settings(FUZZ, max_examples=70)
@given(which=st.sampled_from(["lab_sim", "lab_real"]), content=st.data(), also_solve=st.integers(0, 3))
def test_fuzz_station_file(which: str, content: st.DataObject, also_solve: int) -> None:
    station = content.draw(input_file(which), label="station")
    with _work_dir() as work:
        table, cal, csv = _existing_outputs(work)
        path = _place(work, "station.yaml", station)
        valid = check_loader(load_station, path)
        key = "sim_pos" if which == "lab_sim" else "real_pos"
        rc = check_run(work, ["tables", path, "--key", key, "-o", str(table)])
        if rc == 0:
            assert key in read_lab_file(table).data and "sim_pos" in read_lab_file(table).data
        check_run(work, ["check-table", str(LAB_TABLE), "--key", key, "--calibration", path], allowed=(0, 1, 2))
        rc = check_run(work, ["calibrate", "--taught", str(TAUGHT), "--base", path, "-o", str(cal)])
        if rc == 0:
            load_station(cal)
        rc = check_run(work, ["plan", "--start", "1", "--end", "3", "--blocks", "1", "--no-collision",
                              "--calibration", path, "--csv", str(csv)])
        if rc == 0:
            assert csv.read_text().startswith("t,q1,q2,q3,q4,q5,q6,qd1,")
        if not valid or also_solve == 0:
            check_run(work, ["solve", "--start", "1", "--end", "3", "--blocks", "1", "--calibration", path],
                      allowed=(0, 2, 3))


@settings(FUZZ, max_examples=50)
@given(content=st.data())
def test_fuzz_taught_points_file(content: st.DataObject) -> None:
    taught = content.draw(input_file("taught"), label="taught")
    with _work_dir() as work:
        _, cal, _ = _existing_outputs(work)
        path = _place(work, "taught.yaml", taught)
        check_loader(load_taught, path)
        rc = check_run(work, ["calibrate", "--taught", path, "--base", "lab_real", "-o", str(cal)])
        if rc == 0:
            load_station(cal)


@settings(FUZZ, max_examples=50)
@given(content=st.data())
def test_fuzz_lab_table_file(content: st.DataObject) -> None:
    lab = content.draw(input_file("table"), label="table")
    with _work_dir() as work:
        _, cal, _ = _existing_outputs(work)
        path = _place(work, "hand.yaml", lab)
        check_loader(read_lab_file, path)
        check_run(work, ["check-table", path, "--key", "real_pos", "--calibration", "lab_real"], allowed=(0, 1, 2))
        rc = check_run(work, ["calibrate", "--from-table", path, "--key", "real_pos", "--base", "lab_real",
                              "-o", str(cal)])
        if rc == 0:
            load_station(cal)
        # The mutated file as an existing output: updated only if it is a valid lab file, else left untouched.
        other = read_lab_file(LAB_TABLE).data["sim_pos"]
        rc = check_run(work, ["tables", "lab_real", "--key", "real_pos", "-o", path])
        if rc == 0:
            data = read_lab_file(path).data
            assert "real_pos" in data and data.get("sim_pos", other) is not None


NUMBERS = st.one_of(st.sampled_from(["nan", "inf", "-inf", "-1", "0", "1e-9", "1e9", "1e309", "", " ", "0x10",
                                     "1_0", "\u0663", "9" * 60, "1e-320", "3.", "-0", "true", "1/2", "\x00",
                                     "1.5", "0.3", "10", "125", "500", "2"]),
                    st.floats(allow_nan=True, allow_infinity=True).map(repr),
                    st.integers(-2**70, 2**70).map(str))


@settings(FUZZ, max_examples=80)
@given(command=st.sampled_from(["plan", "solve", "check-table"]), values=st.lists(NUMBERS, min_size=1, max_size=3),
       flags=st.lists(st.integers(0, 20), min_size=3, max_size=3))
def test_fuzz_numeric_options(command: str, values: list[str], flags: list[int]) -> None:
    options = {
        "plan": ["--speed", "--rate", "--dwell", "--blocks", "--start", "--end"],
        # A solve instance that is always invalid (start == end): the options are checked, nothing is simulated.
        "solve": ["--speed", "--seed", "--blocks", "--remove-block", "--drop-during-move"],
        "check-table": ["--tol-mm", "--tol-deg"],
    }[command]
    argv = {"plan": ["plan", "--start", "1", "--end", "3", "--blocks", "1", "--no-collision"],
            "solve": ["solve", "--start", "2", "--end", "2"],
            "check-table": ["check-table", str(LAB_TABLE), "--key", "real_pos", "--calibration", "lab_real"]}[command]
    argv = list(argv)
    for value, flag in zip(values, flags, strict=False):
        argv += [options[flag % len(options)], value]
    with _work_dir() as work:
        rc = check_run(work, argv, allowed=(0, 1, 2) if command == "check-table" else (0, 2))
        if command == "solve":
            assert rc == 2


@settings(FUZZ, max_examples=25)
@given(name=st.text(min_size=1, max_size=40).filter(lambda s: "\x00" not in s and "/" not in s and s not in
                                                    {".", ".."}))
def test_fuzz_output_names(name: str) -> None:
    # Any file name (newlines, escapes, non-ASCII) for the output: written, or refused in one line.
    with _work_dir() as work:
        out = work / name
        rc = check_run(work, ["tables", "lab_real", "--key", "real_pos", "-o", str(out)])
        if rc == 0:
            assert set(read_lab_file(out).data) == {"real_pos"}


@pytest.mark.parametrize("hostile", ["fifo", "dev-zero", "laughs", "deep"])
def test_hostile_inputs_in_a_subprocess_exit_2_quickly(hostile: str, tmp_path: Path) -> None:
    content: bytes | str = {"laughs": HOSTILE_TEXTS[0], "deep": HOSTILE_TEXTS[2]}.get(hostile, hostile)
    path = _place(tmp_path, "station.yaml", content)
    out = tmp_path / "out.yaml"
    res = subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "tables", path, "--key", "sim_pos", "-o", str(out)],
                         capture_output=True, text=True, timeout=60)
    assert res.returncode == 2, res.stderr
    assert res.stderr.count("\n") == 1 and res.stderr.startswith("ur3hanoi: error: ") and res.stdout == ""
    assert not out.exists()
