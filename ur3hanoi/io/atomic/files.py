"""Writing a file atomically: text through an unnamed temporary (:class:`Output`), or a named temporary another
program fills (:class:`PendingFile`)."""

from __future__ import annotations

import contextlib
import errno
import os
import stat
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi.errors import printable
from ur3hanoi.io.atomic.paths import check_file, refuse, resolve
from ur3hanoi.io.atomic.temporaries import NO_TMPFILE, remove_stale_temporaries, temporary_name

ANONYMOUS_TEMPORARIES = True
"""Write text through an unnamed ``O_TMPFILE`` first (False: always a named temporary; for tests)."""


def fsync_dir(directory: Path | int) -> None:
    """Make a rename durable (best effort: some filesystems refuse to fsync a directory)."""
    with contextlib.suppress(OSError):
        fd = directory if isinstance(directory, int) else os.open(directory, os.O_RDONLY | os.O_DIRECTORY |
                                                                  os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            if not isinstance(directory, int):
                os.close(fd)


def existing_mode(path: Path) -> int | None:
    try:
        return stat.S_IMODE(os.stat(path).st_mode)
    except OSError:
        return None


def _fill(fd: int, data: bytes, mode: int | None) -> None:
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
    if mode is not None:
        os.fchmod(fd, mode)
    os.fsync(fd)


def _rename_into_place(dfd: int, tmp: str, name: str) -> None:
    try:
        os.replace(tmp, name, src_dir_fd=dfd, dst_dir_fd=dfd)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp, dir_fd=dfd)
        raise


def _named_from_anonymous(dfd: int, data: bytes, mode: int | None) -> str | None:
    """Write ``data`` to an unnamed file in the directory ``dfd`` and give it a temporary name (None: O_TMPFILE or
    /proc is unavailable, write a named temporary instead)."""
    try:
        fd = os.open(".", os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o666, dir_fd=dfd)
    except OSError as exc:
        if exc.errno in NO_TMPFILE:
            return None
        raise
    try:
        _fill(fd, data, mode)
        tmp = temporary_name()
        try:
            os.link(f"/proc/self/fd/{fd}", tmp, dst_dir_fd=dfd, follow_symlinks=True)  # linkat(AT_SYMLINK_FOLLOW)
        except OSError as exc:
            if exc.errno in (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EIO):
                raise
            return None  # no /proc (or no linkat through it)
        return tmp
    finally:
        os.close(fd)


def _write_in(dfd: int, name: str, data: bytes, mode: int | None) -> None:
    tmp = _named_from_anonymous(dfd, data, mode) if ANONYMOUS_TEMPORARIES else None
    if tmp is None:
        tmp = temporary_name()
        fd = os.open(tmp, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC | os.O_NOFOLLOW, 0o666, dir_fd=dfd)
        try:
            _fill(fd, data, mode)
        except BaseException:
            with contextlib.suppress(OSError):
                os.unlink(tmp, dir_fd=dfd)
            raise
        finally:
            os.close(fd)
    _rename_into_place(dfd, tmp, name)
    fsync_dir(dfd)


class PendingFile:
    """A named temporary file beside an output, for a program that needs a path (ffmpeg): ``path`` (absolute, the
    target's extension), then :meth:`commit` (rename over the target) or :meth:`discard` (remove it)."""

    def __init__(self, out: Output, suffix: str) -> None:
        self.out = out
        remove_stale_temporaries(out.path.parent)
        self.path = out.path.parent / temporary_name(suffix)
        try:
            os.close(os.open(self.path, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC | os.O_NOFOLLOW, 0o666))
        except OSError as exc:
            raise refuse(out.shown, f"{exc.strerror} (in {printable(out.path.parent)})") from None

    def commit(self) -> Path:
        """Rename the temporary over the target (an existing target keeps its permissions); returns the target."""
        try:
            mode = existing_mode(self.out.path)
            if mode is not None:
                os.chmod(self.path, mode)
            os.replace(self.path, self.out.path)
        except OSError as exc:
            self.discard()
            raise refuse(self.out.shown, f"{exc.strerror or exc}; nothing was written") from None
        fsync_dir(self.out.path.parent)
        return self.out.path

    def discard(self) -> None:
        with contextlib.suppress(OSError):
            os.unlink(self.path)


class Output:
    """A checked output path. ``path`` is the file actually replaced (a symlink's target); ``shown`` the name
    the user gave, for messages."""

    def __init__(self, path: Path, shown: str) -> None:
        self.path = path
        self.shown = shown

    def exists(self) -> bool:
        return self.path.exists()

    def write_bytes(self, data: bytes) -> None:
        """Replace the file with ``data`` atomically (pictures, pages)."""
        self.write(data)

    def write(self, text: str | bytes) -> None:
        """Replace the file with ``text`` (UTF-8) atomically; see the module docstring."""
        data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
        parent = self.path.parent
        remove_stale_temporaries(parent)
        try:
            dfd = os.open(parent, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        except OSError as exc:
            raise refuse(self.shown, f"{exc.strerror} (in {printable(parent)})") from None
        try:
            _write_in(dfd, self.path.name, data, existing_mode(self.path))
        except OSError as exc:
            raise refuse(self.shown, f"{exc.strerror or exc}; nothing was written") from None
        finally:
            os.close(dfd)

    def pending(self, suffix: str) -> PendingFile:
        """A temporary file beside the target for another program to write (``suffix``: e.g. ``.mp4``)."""
        return PendingFile(self, suffix)


def check_output(path: str | Path, *, inputs: Sequence[str | Path] = ()) -> Output:
    """Check that ``path`` can be written (see the module docstring) without writing or locking anything.

    Raises:
        OutputError: the path is ``-``, an input file, a directory, a FIFO or device, a symlink planted in a
            sticky directory, or its directory is missing or does not accept new files.
    """
    target, shown = resolve(path)
    check_file(target, shown, inputs)
    return Output(target, shown)
