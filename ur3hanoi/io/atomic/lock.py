"""The lock of a read-modify-write: an exclusive ``flock`` on a lock file beside the output."""

from __future__ import annotations

import contextlib
import fcntl
import os
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from ur3hanoi.errors import OutputError, printable
from ur3hanoi.io.atomic.files import Output
from ur3hanoi.io.atomic.paths import check_file, refuse, resolve, user_name
from ur3hanoi.io.atomic.temporaries import lock_file_name, same_file

LOCK_TIMEOUT_S = 60.0
"""Longest wait [s] for another writer of the same file before giving up."""


def _flock(fd: int, shown: str, lock_path: Path, deadline: float) -> None:
    while True:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return
        except BlockingIOError:
            if time.monotonic() > deadline:
                raise refuse(shown, f"another process has held {printable(lock_path)} for {LOCK_TIMEOUT_S:g} s "
                                     "(remove it if no ur3hanoi is running)") from None
            time.sleep(0.005)


def _foreign_lock(shown: str, lock_path: Path, uid: int) -> OutputError:
    return refuse(shown, f"the lock file {printable(lock_path)} belongs to {user_name(uid)}, not to you: another user "
                          "is writing this file (remove the lock file if they are not)")


def _open_lock(lock_path: Path, shown: str) -> int:
    try:
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW | os.O_NONBLOCK, 0o600)
    except OSError as exc:
        with contextlib.suppress(OSError):
            uid = os.lstat(lock_path).st_uid
            if uid != os.geteuid():
                raise _foreign_lock(shown, lock_path, uid) from None
        raise refuse(shown, f"cannot create the lock file {printable(lock_path)} ({exc.strerror})") from None
    uid = os.fstat(fd).st_uid
    if uid != os.geteuid():
        os.close(fd)
        raise _foreign_lock(shown, lock_path, uid)
    return fd


@contextlib.contextmanager
def file_lock(target: Path, shown: str) -> Iterator[None]:
    """Exclusive lock on :func:`lock_file_name` beside ``target``, removed again when released.

    The holder unlinks the lock file before it lets go; a waiter that then gets the lock on the unlinked file sees
    that the path no longer names it and starts over, so exactly one process at a time holds the lock that counts.
    """
    lock_path = target.parent / lock_file_name(target.name)
    deadline = time.monotonic() + LOCK_TIMEOUT_S
    while True:
        fd = _open_lock(lock_path, shown)
        try:
            _flock(fd, shown, lock_path, deadline)
            if same_file(os.fstat(fd), os.stat(lock_path)):
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
    target, shown = resolve(path)
    check_file(target, shown, inputs)  # refuse before creating the lock file
    with file_lock(target, shown):
        check_file(target, shown, inputs)
        yield Output(target, shown)


def atomic_write(path: str | Path, text: str | bytes, *, inputs: Sequence[str | Path] = ()) -> Path:
    """Check ``path``, then replace it with ``text`` atomically (see the module docstring).

    Returns:
        The file actually written (a symlink's target).

    Raises:
        OutputError: refused path or failed write; nothing was changed.
    """
    with locked_output(path, inputs=inputs) as out:
        out.write(text)
    return out.path
