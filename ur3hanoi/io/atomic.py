"""The one writer of ur3hanoi: output paths checked first, atomic replacement, a lock for read-modify-write.

Every output (lab tables, calibrations, plan CSVs) goes through :func:`atomic_write` or :func:`locked_output`:

- The path is checked before anything is written: it must not be an input of the same command, a directory, a
  FIFO, socket or device, and its directory must exist and be writable. A refused path raises
  :class:`~ur3hanoi.errors.OutputError` naming it.
- A symlink is written through: its target is replaced (atomically), the link stays, as editors do.
- The text goes to a temporary file beside the target, is flushed to disk and renamed over the target
  (``os.replace``). Any failure (a full disk included) removes the temporary file and leaves an existing target
  byte-identical. A new file gets the usual permissions (0666 less the umask), an existing one keeps its own.
- :func:`locked_output` holds an exclusive ``fcntl.flock`` on a lock file beside the target (``.<name>.lock``)
  while the caller reads the old file and writes the new one, so concurrent writers of one file never lose each
  other's updates. The lock file is removed when the lock is released: nothing is left behind.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import stat
import tempfile
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from ur3hanoi.errors import OutputError, printable
from ur3hanoi.io.reading import file_kind

LOCK_TIMEOUT_S = 60.0
"""Longest wait [s] for another writer of the same directory before giving up."""


def _refuse(shown: str, problem: str) -> OutputError:
    return OutputError(f"cannot write {printable(shown)}: {problem}")


class Output:
    """A checked output path. ``path`` is the file actually replaced (a symlink's target); ``shown`` the name
    the user gave, for messages."""

    def __init__(self, path: Path, shown: str) -> None:
        self.path = path
        self.shown = shown

    def exists(self) -> bool:
        return self.path.exists()

    def write(self, text: str) -> None:
        """Replace the file with ``text`` (UTF-8) atomically; see the module docstring."""
        self.write_bytes(text.encode("utf-8"))

    def write_bytes(self, data: bytes) -> None:
        """Replace the file with ``data`` atomically (pictures); see the module docstring."""
        try:
            fd, tmp = tempfile.mkstemp(prefix=f".{self.path.name}.", suffix=".tmp", dir=self.path.parent)
        except OSError as exc:
            raise _refuse(self.shown, f"{exc.strerror} (in {printable(self.path.parent)})") from None
        try:
            with os.fdopen(fd, "wb") as f:
                f.write(data)
                f.flush()
                os.fsync(f.fileno())
            try:
                mode = stat.S_IMODE(os.stat(self.path).st_mode)
            except FileNotFoundError:  # mkstemp creates 0600: a new file gets 0666 less the umask
                umask = os.umask(0)
                os.umask(umask)
                mode = 0o666 & ~umask
            os.chmod(tmp, mode)
            os.replace(tmp, self.path)
        except BaseException as exc:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
            if isinstance(exc, OSError):
                raise _refuse(self.shown, f"{exc.strerror or exc}; nothing was written") from None
            raise
        _fsync_dir(self.path.parent)


def _fsync_dir(directory: Path) -> None:
    """Make the rename durable (best effort: some filesystems refuse to fsync a directory)."""
    with contextlib.suppress(OSError):
        fd = os.open(directory, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)


def _same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _resolve(path: str | Path) -> tuple[Path, str]:
    shown = str(path)
    if not shown:
        raise _refuse("''", "the path is empty")
    if "\0" in shown:
        raise _refuse(shown, "the path contains a NUL character")
    return Path(os.path.realpath(shown)), shown


def _check(target: Path, shown: str, inputs: Sequence[str | Path]) -> None:
    try:
        st: os.stat_result | None = os.stat(target)
    except FileNotFoundError:
        st = None
    except OSError as exc:
        raise _refuse(shown, exc.strerror or str(exc)) from None
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            raise _refuse(shown, f"it is {file_kind(st.st_mode)}: expected a regular file (or a new one)")
        for src in inputs:
            try:
                same = _same_file(st, os.stat(src))
            except (OSError, ValueError):
                continue
            if same:
                raise _refuse(shown, f"it is also an input of this command ({printable(src)}): choose another "
                                     "output file")
    parent = target.parent
    try:
        pst = os.stat(parent)
    except FileNotFoundError:
        raise _refuse(shown, f"the directory {printable(parent)} does not exist") from None
    except OSError as exc:
        raise _refuse(shown, f"the directory {printable(parent)} is unusable ({exc.strerror})") from None
    if not stat.S_ISDIR(pst.st_mode):
        raise _refuse(shown, f"{printable(parent)} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise _refuse(shown, f"the directory {printable(parent)} is not writable")


def check_output(path: str | Path, *, inputs: Sequence[str | Path] = ()) -> Output:
    """Check that ``path`` can be written (see the module docstring) without writing or locking anything.

    Raises:
        OutputError: the path is an input file, a directory, a FIFO or device, or its directory is missing or
            read-only.
    """
    target, shown = _resolve(path)
    _check(target, shown, inputs)
    return Output(target, shown)


def _flock(fd: int, shown: str, lock_path: Path, deadline: float) -> None:
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if time.monotonic() > deadline:
                raise _refuse(shown, f"another process has held {printable(lock_path)} for {LOCK_TIMEOUT_S:g} s "
                                     "(remove it if no ur3hanoi is running)") from None
            time.sleep(0.005)


@contextlib.contextmanager
def _file_lock(target: Path, shown: str) -> Iterator[None]:
    """Exclusive lock on ``.<name>.lock`` beside ``target``, removed again when released.

    The holder unlinks the lock file before it lets go; a waiter that then gets the lock on the unlinked file sees
    that the path no longer names it and starts over, so exactly one process at a time holds the lock that counts.
    """
    lock_path = target.parent / f".{target.name}.lock"
    deadline = time.monotonic() + LOCK_TIMEOUT_S
    while True:
        try:
            fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW, 0o600)
        except OSError as exc:
            raise _refuse(shown, f"cannot create the lock file {printable(lock_path)} ({exc.strerror})") from None
        try:
            _flock(fd, shown, lock_path, deadline)
            if _same_file(os.fstat(fd), os.stat(lock_path)):
                break
        except FileNotFoundError:
            pass  # unlinked by the previous holder: start over
        except BaseException:
            os.close(fd)
            raise
        os.close(fd)
    try:
        yield
    finally:
        with contextlib.suppress(OSError):
            os.unlink(lock_path)
        os.close(fd)  # releases the lock


@contextlib.contextmanager
def locked_output(path: str | Path, *, inputs: Sequence[str | Path] = ()) -> Iterator[Output]:
    """A checked :class:`Output` with an exclusive lock held for the ``with`` block.

    Read the old file and call :meth:`Output.write` inside the block: concurrent writers are serialized.
    """
    target, shown = _resolve(path)
    _check(target, shown, inputs)  # refuse before creating the lock file
    with _file_lock(target, shown):
        _check(target, shown, inputs)
        yield Output(target, shown)


def atomic_write(path: str | Path, text: str, *, inputs: Sequence[str | Path] = ()) -> Path:
    """Check ``path``, then replace it with ``text`` atomically (see the module docstring).

    Returns:
        The file actually written (a symlink's target).

    Raises:
        OutputError: refused path or failed write; nothing was changed.
    """
    with locked_output(path, inputs=inputs) as out:
        out.write(text)
    return out.path
