"""The writer: refused outputs, atomic replacement, symlinks written through, no lost update under concurrency."""

from __future__ import annotations

import errno
import fcntl
import multiprocessing
import os
import signal
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
import yaml

from ur3hanoi.errors import OutputError
from ur3hanoi.io.atomic import atomic_write, check_output, lock_file_name, locked_output
from ur3hanoi.io.atomic import files as atomic_files
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
        ("open", OSError(errno.EROFS, "Read-only file system"), "Read-only file system"),
    ],
)
@pytest.mark.parametrize("anonymous", [True, False], ids=["O_TMPFILE", "named"])
def test_failed_write_leaves_old_file_and_no_temp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, patch: str,
                                                  exc: OSError, match: str, anonymous: bool) -> None:
    out = tmp_path / "a.txt"
    out.write_text("old\n")
    monkeypatch.setattr(atomic_files, "ANONYMOUS_TEMPORARIES", anonymous)
    real = getattr(os, patch)

    def fail(*args: Any, **kwargs: Any) -> Any:
        if patch == "open" and not args[1] & (os.O_CREAT | os.O_TMPFILE):  # directories still open
            return real(*args, **kwargs)
        raise exc

    monkeypatch.setattr(os, patch, fail)
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


# ------------------------------------------------------------------------------------ names, SIGKILL, symlinks

OTHER_UID = 65534  # nobody: the "other user" who plants links and lock files (tests run as root)


def _sticky_dir(tmp_path: Path) -> Path:
    """A shared sticky world-writable directory like /tmp, owned by root (the caller here)."""
    shared = tmp_path / "shared"
    shared.mkdir()
    shared.chmod(0o1777)
    return shared


@pytest.mark.parametrize("n_bytes", [250, 254, 255])
def test_file_names_up_to_name_max_are_written(tmp_path: Path, n_bytes: int) -> None:
    name = "é" * ((n_bytes - 4) // 2) + "x" * ((n_bytes - 4) % 2) + ".txt"  # multi-byte UTF-8 counts in bytes
    assert len(os.fsencode(name)) == n_bytes
    out = tmp_path / name
    atomic_write(out, "one\n")
    with locked_output(out) as o:
        o.write(o.path.read_text() + "two\n")
    assert out.read_text() == "one\ntwo\n"
    assert _listing(tmp_path) == [name]


_KILLED_WRITER = """
import os, sys
from ur3hanoi.io import atomic
from ur3hanoi.io.atomic import files
files.ANONYMOUS_TEMPORARIES = sys.argv[2] == "anonymous"
def stall(fd):
    print("writing", flush=True)  # the text is in the temporary file, not yet renamed: wait to be killed
    import time
    time.sleep(60)
os.fsync = stall
atomic.atomic_write(sys.argv[1], "new\\n" * 100000)
"""


def _kill_mid_write(out: Path, mode: str) -> None:
    proc = subprocess.Popen([sys.executable, "-c", _KILLED_WRITER, str(out), mode], stdout=subprocess.PIPE,
                            text=True)
    try:
        assert proc.stdout is not None and proc.stdout.readline() == "writing\n"
        proc.send_signal(signal.SIGKILL)
    finally:
        proc.wait(timeout=30)
    assert proc.returncode == -signal.SIGKILL


def test_sigkill_mid_write_leaves_no_temporary_file(tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text("old\n")
    _kill_mid_write(out, "anonymous")  # O_TMPFILE: the text never had a name
    assert out.read_text() == "old\n"
    assert _listing(tmp_path) == sorted(["lab2_data.yaml", lock_file_name("lab2_data.yaml")])  # the held lock...
    atomic_write(tmp_path / "other.txt", "x\n")  # ...is removed by the next write into the directory
    assert _listing(tmp_path) == ["lab2_data.yaml", "other.txt"]


def test_a_later_write_removes_the_named_temporary_of_a_killed_writer(tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text("old\n")
    _kill_mid_write(out, "named")  # the fallback where O_TMPFILE is unsupported: a named temporary is left...
    left = [n for n in _listing(tmp_path) if n not in ("lab2_data.yaml", lock_file_name("lab2_data.yaml"))]
    assert len(left) == 1 and out.read_text() == "old\n"
    live = tmp_path / left[0].replace(left[0].split("-")[1], str(os.getpid()), 1)  # one of a running process
    live.write_text("busy\n")
    atomic_write(tmp_path / "other.txt", "x\n")  # ...and removed by the next write into the directory
    assert _listing(tmp_path) == sorted(["lab2_data.yaml", "other.txt", live.name])


@pytest.mark.skipif(os.geteuid() != 0, reason="planting another user's link needs root (os.lchown)")
@pytest.mark.parametrize("write", ["atomic_write", "locked_output"])
def test_a_link_planted_by_another_user_in_a_sticky_directory_is_not_followed(tmp_path: Path, write: str) -> None:
    victim = tmp_path / "victim.txt"
    victim.write_text("precious\n")
    shared = _sticky_dir(tmp_path)
    link = shared / "plan.csv"
    link.symlink_to(victim)
    os.lchown(link, OTHER_UID, OTHER_UID)
    with pytest.raises(OutputError, match=r"symbolic link of user .*uid 65534.* sticky directory") as info:
        if write == "atomic_write":
            atomic_write(link, "evil\n")
        else:
            with locked_output(link) as out:
                out.write("evil\n")
    assert "\n" not in str(info.value)
    assert victim.read_text() == "precious\n" and _listing(shared) == ["plan.csv"]
    # Also when the planted link is a directory on the way, or check_output alone is asked.
    (shared / "d").symlink_to(tmp_path)
    os.lchown(shared / "d", OTHER_UID, OTHER_UID)
    with pytest.raises(OutputError, match="sticky directory"):
        check_output(shared / "d" / "victim.txt")
    assert victim.read_text() == "precious\n"


@pytest.mark.skipif(os.geteuid() != 0, reason="chown needs root")
def test_links_of_the_caller_or_the_directory_owner_are_followed(tmp_path: Path) -> None:
    target = tmp_path / "real.txt"
    shared = _sticky_dir(tmp_path)
    mine = shared / "mine.txt"
    mine.symlink_to(target)  # the caller's own link
    atomic_write(mine, "a\n")
    assert target.read_text() == "a\n"
    owned = tmp_path / "owned"  # a sticky directory of the other user, whose own link is trusted
    owned.mkdir()
    owned.chmod(0o1777)
    os.chown(owned, OTHER_UID, OTHER_UID)
    theirs = owned / "theirs.txt"
    theirs.symlink_to(target)
    os.lchown(theirs, OTHER_UID, OTHER_UID)
    atomic_write(theirs, "b\n")
    assert target.read_text() == "b\n"
    plain = tmp_path / "plain"  # not sticky: any link is followed, as the kernel does
    plain.mkdir()
    (plain / "l.txt").symlink_to(target)
    os.lchown(plain / "l.txt", OTHER_UID, OTHER_UID)
    atomic_write(plain / "l.txt", "c\n")
    assert target.read_text() == "c\n"


@pytest.mark.skipif(os.geteuid() != 0, reason="chown needs root")
def test_a_lock_file_of_another_user_is_a_clear_error_not_a_wait(tmp_path: Path) -> None:
    out = tmp_path / "lab2_data.yaml"
    out.write_text("old\n")
    lock = tmp_path / lock_file_name("lab2_data.yaml")
    lock.write_text("")
    os.chown(lock, OTHER_UID, OTHER_UID)
    holder = os.open(lock, os.O_RDWR)
    fcntl.flock(holder, fcntl.LOCK_EX)  # the other user's writer holds it
    try:
        with pytest.raises(OutputError, match=r"the lock file .*\.lock belongs to .*uid 65534"):
            atomic_write(out, "new\n")
    finally:
        os.close(holder)
    assert out.read_text() == "old\n"


@pytest.mark.parametrize(("path", "match"), [
    ("-", "standard output"),
    ("/proc/x.txt", "does not accept new files"),
])
def test_outputs_that_cannot_be_written_are_refused_before_writing(path: str, match: str) -> None:
    with pytest.raises(OutputError, match=match) as info:
        check_output(path)
    assert "\n" not in str(info.value)


def test_a_removed_working_directory_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    gone = tmp_path / "gone"
    gone.mkdir()
    monkeypatch.chdir(gone)
    gone.rmdir()
    with pytest.raises(OutputError, match="the current directory is unusable"):
        check_output("x.txt")
