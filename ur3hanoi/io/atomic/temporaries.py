"""Temporary and lock file names beside an output, and the removal of those a killed writer left behind."""

from __future__ import annotations

import errno
import fcntl
import hashlib
import os
import re
import shutil
import stat
from pathlib import Path

TEMP_PREFIX = ".ur3hanoi-"
"""Start of every temporary and lock file name this module creates."""


_TEMP_NAME = re.compile(r"\.ur3hanoi-(\d{1,10})-([0-9a-f]{8})-[0-9a-f]{8}\.[0-9A-Za-z]{1,8}")


_LOCK_NAME = re.compile(r"\.ur3hanoi-[0-9a-f]{16}\.lock")


NO_TMPFILE = {errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL}  # O_TMPFILE unsupported (not "not allowed")


def same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _host_tag() -> str:
    return hashlib.sha256(os.uname().nodename.encode("utf-8", "surrogateescape")).hexdigest()[:8]


def temporary_name(suffix: str = ".tmp") -> str:
    """A fresh temporary name ``.ur3hanoi-<pid>-<host>-<random><suffix>`` (under 50 bytes, whatever the target)."""
    return f"{TEMP_PREFIX}{os.getpid()}-{_host_tag()}-{os.urandom(4).hex()}{suffix}"


def lock_file_name(name: str) -> str:
    """The lock file beside the file ``name``: ``.ur3hanoi-<16 hex digits of sha256(name)>.lock``."""
    return f"{TEMP_PREFIX}{hashlib.sha256(os.fsencode(name)).hexdigest()[:16]}.lock"


def _process_gone(pid: int) -> bool:
    if pid == os.getpid():
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    except PermissionError:  # alive, another user's
        return False
    except (OverflowError, ValueError):  # not a pid at all
        return True
    return False


def _remove_unlocked(path: str) -> bool:
    """Remove a lock file nobody holds (following the lock protocol: unlink while holding it)."""
    try:
        fd = os.open(path, os.O_RDWR | os.O_NOFOLLOW | os.O_CLOEXEC | os.O_NONBLOCK)
    except OSError:
        return False
    try:
        if os.fstat(fd).st_uid != os.geteuid():
            return False
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        if same_file(os.fstat(fd), os.stat(path, follow_symlinks=False)):
            os.unlink(path)
            return True
        return False
    except OSError:
        return False
    finally:
        os.close(fd)


def remove_stale_temporaries(directory: str | Path) -> list[str]:
    """Remove, in ``directory``, the temporaries this user left on this host from processes that are gone, and
    lock files nobody holds. Best effort (errors are ignored); returns the names removed."""
    removed: list[str] = []
    tag, euid = _host_tag(), os.geteuid()
    try:
        entries = list(os.scandir(directory))
    except OSError:
        return removed
    for entry in entries:
        if not entry.name.startswith(TEMP_PREFIX):
            continue
        if _LOCK_NAME.fullmatch(entry.name):
            if _remove_unlocked(entry.path):
                removed.append(entry.name)
            continue
        m = _TEMP_NAME.fullmatch(entry.name)
        if m is None or m.group(2) != tag or not _process_gone(int(m.group(1))):
            continue
        try:
            st = entry.stat(follow_symlinks=False)
            if st.st_uid != euid:
                continue
            if stat.S_ISDIR(st.st_mode):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
        except OSError:
            continue
        removed.append(entry.name)
    return removed
