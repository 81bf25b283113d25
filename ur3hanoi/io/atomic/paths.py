"""Checking an output path before anything is written: resolving it under the ``protected_symlinks`` rule,
refusing what cannot be written, probing that its directory accepts a new file."""

from __future__ import annotations

import contextlib
import errno
import os
import pwd
import stat
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi.errors import OutputError, printable
from ur3hanoi.io.atomic.temporaries import NO_TMPFILE, same_file, temporary_name
from ur3hanoi.io.reading import file_kind

_MAX_LINKS = 40  # the kernel's limit of symlinks followed in one path (ELOOP beyond)


def refuse(shown: str, problem: str) -> OutputError:
    return OutputError(f"cannot write {printable(shown)}: {problem}")


def user_name(uid: int) -> str:
    try:
        return f"user {pwd.getpwuid(uid).pw_name!r} (uid {uid})"
    except KeyError:
        return f"uid {uid}"


def _check_link(directory: str, link: str, link_st: os.stat_result, shown: str) -> None:
    """The kernel's ``protected_symlinks`` rule: in a sticky world-writable directory, follow only a link owned by
    the directory's owner or by the caller."""
    dir_st = os.stat(directory)
    if not (dir_st.st_mode & stat.S_ISVTX and dir_st.st_mode & stat.S_IWOTH):
        return
    if link_st.st_uid in (dir_st.st_uid, os.geteuid()):
        return
    raise refuse(shown, f"{printable(link)} is a symbolic link of {user_name(link_st.st_uid)} in the shared sticky "
                         f"directory {printable(directory)}: not followed (the kernel's protected_symlinks rule); "
                         "remove the link or choose another path")


def resolve(path: str | Path) -> tuple[Path, str]:
    """The absolute file a path names, every symlink on the way followed under :func:`_check_link`."""
    shown = str(path)
    if not shown:
        raise refuse("''", "the path is empty")
    if "\0" in shown:
        raise refuse(shown, "the path contains a NUL character")
    if shown == "-":
        raise refuse(shown, "standard output is not supported for this output: give a file name (./- for a file "
                             "named '-')")
    try:
        current = "/" if shown.startswith("/") else os.getcwd()
    except OSError as exc:  # the working directory was removed
        raise refuse(shown, f"the current directory is unusable ({exc.strerror})") from None
    parts = list(reversed(shown.split("/")))  # a stack: next component last
    links = 0
    while parts:
        comp = parts.pop()
        if comp in ("", "."):
            continue
        if comp == "..":
            current = os.path.dirname(current)
            continue
        candidate = os.path.join(current, comp)
        try:
            st = os.lstat(candidate)
        except OSError:  # missing, or not a directory on the way: the checks name it
            current = os.path.normpath(os.path.join(candidate, *reversed(parts)))
            break
        if stat.S_ISLNK(st.st_mode):
            links += 1
            if links > _MAX_LINKS:
                raise refuse(shown, os.strerror(errno.ELOOP))
            _check_link(current, candidate, st, shown)
            target = os.readlink(candidate)
            if target.startswith("/"):
                current = "/"
            parts.extend(reversed(target.split("/")))
            continue
        current = candidate
    return Path(current), shown


def probe(directory: Path, shown: str) -> None:
    """Refuse a directory that does not accept a new file, creating none (an unnamed O_TMPFILE where supported)."""
    try:
        fd = os.open(directory, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o600)
    except OSError as exc:
        if exc.errno not in NO_TMPFILE:
            raise refuse(shown, f"the directory {printable(directory)} is not writable ({exc.strerror})") from None
        probe = directory / temporary_name(".probe")
        try:
            fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC | os.O_NOFOLLOW, 0o600)
        except OSError as exc2:
            raise refuse(shown, f"the directory {printable(directory)} does not accept new files "
                                 f"({exc2.strerror})") from None
        with contextlib.suppress(OSError):
            os.unlink(probe)
    os.close(fd)


def check_parent(parent: Path, shown: str) -> None:
    try:
        pst = os.stat(parent)
    except FileNotFoundError:
        raise refuse(shown, f"the directory {printable(parent)} does not exist (create it first: mkdir -p)") from None
    except OSError as exc:
        raise refuse(shown, f"the directory {printable(parent)} is unusable ({exc.strerror})") from None
    if not stat.S_ISDIR(pst.st_mode):
        raise refuse(shown, f"{printable(parent)} is not a directory")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise refuse(shown, f"the directory {printable(parent)} is not writable")
    probe(parent, shown)


def stat_or_none(target: Path, shown: str) -> os.stat_result | None:
    try:
        return os.stat(target)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise refuse(shown, exc.strerror or str(exc)) from None


def check_inputs(st: os.stat_result, shown: str, inputs: Sequence[str | Path]) -> None:
    for src in inputs:
        try:
            same = same_file(st, os.stat(src))
        except (OSError, ValueError):
            continue
        if same:
            raise refuse(shown, f"it is also an input of this command ({printable(src)}): choose another "
                                 "output file")


def check_file(target: Path, shown: str, inputs: Sequence[str | Path]) -> None:
    st = stat_or_none(target, shown)
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            raise refuse(shown, f"it is {file_kind(st.st_mode)}: expected a regular file (or a new one)")
        check_inputs(st, shown, inputs)
    check_parent(target.parent, shown)
