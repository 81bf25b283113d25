"""Read an input file's bytes without ever blocking or reading without bound.

The path is checked with ``os.stat`` before it is opened: directories, FIFOs, sockets and devices (``/dev/zero``,
a terminal) are refused by name, and so is a file over :data:`~ur3hanoi.io.limits.MAX_FILE_BYTES`. The open is
non-blocking and the opened file is checked again (``fstat``), so a path swapped for a FIFO in between cannot hang
the program either.
"""

from __future__ import annotations

import os
import stat
from pathlib import Path

from ur3hanoi.errors import InputError
from ur3hanoi.io.limits import MAX_FILE_BYTES


def file_kind(mode: int) -> str:
    """A reader's name for the file type in ``st_mode`` ("a directory", "a FIFO", ...)."""
    if stat.S_ISDIR(mode):
        return "a directory"
    if stat.S_ISFIFO(mode):
        return "a FIFO (named pipe)"
    if stat.S_ISSOCK(mode):
        return "a socket"
    if stat.S_ISCHR(mode) or stat.S_ISBLK(mode):
        return "a device"
    return "a regular file" if stat.S_ISREG(mode) else "not a regular file"


def _check(st: os.stat_result, source: str, what: str, error: type[InputError]) -> None:
    if not stat.S_ISREG(st.st_mode):
        raise error.file(source, f"is {file_kind(st.st_mode)}, not a {what} (expected a regular file)")
    if st.st_size > MAX_FILE_BYTES:
        raise error.file(source, f"is {st.st_size} bytes, more than a {what} can be "
                                 f"(at most {MAX_FILE_BYTES} bytes)")


def read_input_bytes(path: str | Path, *, what: str, error: type[InputError] = InputError,
                     source: str | None = None, missing_hint: str = "") -> bytes:
    """The bytes of the regular file ``path`` (at most :data:`MAX_FILE_BYTES`).

    Args:
        path: file to read (symlinks are followed).
        what: the file kind for messages ("calibration file").
        error: exception class raised (the file kind's :class:`~ur3hanoi.errors.InputError` subclass).
        source: how the file is named in messages (default ``str(path)``).
        missing_hint: appended to the message when the file does not exist.

    Raises:
        error: the path is missing, unreadable, not a regular file, or too large; the message names it.
    """
    source = str(path) if source is None else source
    try:
        _check(os.stat(path), source, what, error)
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_NOCTTY | os.O_CLOEXEC)
    except ValueError:  # an embedded NUL character
        raise error.file(source, f"cannot read the {what}: the path contains a NUL character") from None
    except OSError as exc:
        hint = missing_hint if isinstance(exc, FileNotFoundError) and missing_hint else ""
        raise error.file(source, f"cannot read the {what} ({exc.strerror}){hint}") from None
    try:
        _check(os.fstat(fd), source, what, error)
        chunks: list[bytes] = []
        size = 0
        while size <= MAX_FILE_BYTES:
            chunk = os.read(fd, MAX_FILE_BYTES + 1 - size)
            if not chunk:
                break
            chunks.append(chunk)
            size += len(chunk)
    except OSError as exc:
        raise error.file(source, f"cannot read the {what} ({exc.strerror})") from None
    finally:
        os.close(fd)
    if size > MAX_FILE_BYTES:  # grew while being read
        raise error.file(source, f"is more than {MAX_FILE_BYTES} bytes, more than a {what} can be")
    return b"".join(chunks)
