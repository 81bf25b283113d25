"""The writer: refused outputs, atomic replacement, symlinks written through, no lost update under concurrency."""

from __future__ import annotations

import errno
import multiprocessing
import os
import tempfile
from pathlib import Path
from typing import Any

import pytest
import yaml

from ur3hanoi.errors import OutputError
from ur3hanoi.io.atomic import atomic_write, check_output, locked_output
from ur3hanoi.io.yaml_loader import parse_yaml


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


def test_write_creates_and_replaces(tmp_path: Path) -> None:
    out = tmp_path / "a.txt"
    assert atomic_write(out, "one\n") == out.resolve()
    atomic_write(out, "two\n")
    assert out.read_text() == "two\n"
    assert _listing(tmp_path) == ["a.txt"]


def test_symlink_is_written_through_atomically(tmp_path: Path) -> None:
    target = tmp_path / "real.txt"
    target.write_text("old\n")
    link = tmp_path / "link.txt"
    link.symlink_to(target)
    assert atomic_write(link, "new\n") == target.resolve()
    assert link.is_symlink() and target.read_text() == "new\n"
    dangling = tmp_path / "dangling.txt"
    dangling.symlink_to(tmp_path / "created.txt")
    atomic_write(dangling, "x\n")
    assert (tmp_path / "created.txt").read_text() == "x\n" and dangling.is_symlink()


@pytest.mark.parametrize(
    ("kind", "match"),
    [
        ("directory", "it is a directory"),
        ("fifo", r"it is a FIFO \(named pipe\)"),
        ("device", "it is a device"),
        ("missing-dir", "the directory .* does not exist"),
        ("parent-is-file", "Not a directory"),
        ("input", r"it is also an input of this command \(.*in.txt\)"),
        ("hardlinked-input", "it is also an input of this command"),
        ("nul", "the path contains a NUL character"),
        ("symlink-loop", "Too many levels of symbolic links"),
    ],
)
def test_refused_outputs_write_nothing(tmp_path: Path, kind: str, match: str) -> None:
    src = tmp_path / "in.txt"
    src.write_text("input\n")
    out: str | Path = tmp_path / "out.txt"
    if kind == "directory":
        out = tmp_path
    elif kind == "fifo":
        os.mkfifo(out)
    elif kind == "device":
        out = "/dev/null"
    elif kind == "missing-dir":
        out = tmp_path / "no" / "out.txt"
    elif kind == "parent-is-file":
        out = src / "out.txt"
    elif kind == "input":
        out = src
    elif kind == "hardlinked-input":
        os.link(src, out)
    elif kind == "nul":
        out = f"{tmp_path}/o\0.txt"
    elif kind == "symlink-loop":
        Path(out).symlink_to(out)
    before = _listing(tmp_path)
    with pytest.raises(OutputError, match=match) as info:
        atomic_write(out, "new\n", inputs=[src])
    assert "\n" not in str(info.value)
    assert src.read_text() == "input\n"
    assert _listing(tmp_path) == before


@pytest.mark.parametrize(
    ("patch", "exc", "match"),
    [
        ("fsync", OSError(errno.ENOSPC, "No space left on device"), "No space left on device; nothing was written"),
        ("replace", OSError(errno.EXDEV, "Invalid cross-device link"), "Invalid cross-device link"),
        ("mkstemp", OSError(errno.EROFS, "Read-only file system"), "Read-only file system"),
    ],
)
def test_failed_write_leaves_old_file_and_no_temp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, patch: str,
                                                  exc: OSError, match: str) -> None:
    out = tmp_path / "a.txt"
    out.write_text("old\n")

    def fail(*args: Any, **kwargs: Any) -> Any:
        raise exc

    monkeypatch.setattr(tempfile if patch == "mkstemp" else os, patch, fail)
    with pytest.raises(OutputError, match=match):
        atomic_write(out, "new\n")
    assert out.read_text() == "old\n"
    assert _listing(tmp_path) == ["a.txt"]


def test_interrupted_write_removes_the_temp_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    out = tmp_path / "a.txt"

    def interrupt(fd: int) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "fsync", interrupt)
    with pytest.raises(KeyboardInterrupt):
        atomic_write(out, "new\n")
    assert _listing(tmp_path) == []


def test_check_output_writes_nothing(tmp_path: Path) -> None:
    out = check_output(tmp_path / "new.txt")
    assert not out.exists() and _listing(tmp_path) == []


# ------------------------------------------------------------------------------------------------ concurrency

WRITERS = 8
ROUNDS = 20


def _writer(path: str, index: int, barrier: Any) -> None:
    """Each round: wait for all writers, then append this round to this writer's own key (read-modify-write)."""
    for r in range(ROUNDS):
        barrier.wait()
        with locked_output(path) as out:
            data = parse_yaml(out.path.read_text(), path) or {}
            data.setdefault(f"writer{index}", []).append(r)
            out.write(yaml.safe_dump(data))


def test_concurrent_writers_never_lose_a_key(tmp_path: Path) -> None:
    path = tmp_path / "shared.yaml"
    path.write_text("{}\n")
    ctx = multiprocessing.get_context("spawn")  # no inherited locks or threads
    barrier = ctx.Barrier(WRITERS)
    procs = [ctx.Process(target=_writer, args=(str(path), i, barrier)) for i in range(WRITERS)]
    for p in procs:
        p.start()
    for p in procs:
        p.join(timeout=120)
    assert [p.exitcode for p in procs] == [0] * WRITERS
    data = parse_yaml(path.read_text(), str(path))
    assert data == {f"writer{i}": list(range(ROUNDS)) for i in range(WRITERS)}
    assert _listing(tmp_path) == ["shared.yaml"]
