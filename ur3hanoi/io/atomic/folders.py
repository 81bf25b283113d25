"""Filling a folder atomically: files go to a temporary folder, moved into place on success."""

from __future__ import annotations

import errno
import os
import re
import shutil
import stat
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi.errors import printable
from ur3hanoi.io.atomic.files import fsync_dir
from ur3hanoi.io.atomic.paths import check_inputs, check_parent, probe, refuse, resolve, stat_or_none
from ur3hanoi.io.atomic.temporaries import remove_stale_temporaries, temporary_name
from ur3hanoi.io.reading import file_kind


class PendingDir:
    """A temporary folder for the files of an :class:`OutputDir`: ``path``, then :meth:`commit` or
    :meth:`discard`. A new folder is renamed into place; into an existing one each file is renamed."""

    def __init__(self, out: OutputDir) -> None:
        self.out = out
        host = out.path if out.path.is_dir() else out.path.parent
        remove_stale_temporaries(host)
        self.path = host / temporary_name(".d")
        try:
            os.mkdir(self.path, 0o777)
        except OSError as exc:
            raise refuse(out.shown, f"{exc.strerror} (in {printable(host)})") from None

    def commit(self, replaces: re.Pattern[str] | None = None) -> Path:
        """Move the files into the folder; files of the folder matching ``replaces`` (a previous run's) that this
        run did not write are removed. Returns the folder."""
        target = self.out.path
        try:
            if self.path.parent != target:  # a new folder: one rename
                try:
                    os.rename(self.path, target)
                    fsync_dir(target.parent)
                    return target
                except OSError as exc:
                    if exc.errno not in (errno.EEXIST, errno.ENOTEMPTY):
                        raise
            names = set(os.listdir(self.path))
            for name in sorted(names):
                os.replace(self.path / name, target / name)
            if replaces is not None:
                for name in os.listdir(target):
                    if name not in names and replaces.fullmatch(name):
                        os.unlink(target / name)
            os.rmdir(self.path)
        except OSError as exc:
            self.discard()
            raise refuse(self.out.shown, f"{exc.strerror or exc}") from None
        fsync_dir(target)
        return target

    def discard(self) -> None:
        shutil.rmtree(self.path, ignore_errors=True)


class OutputDir:
    """A checked output folder (``path``: absolute, symlinks followed; ``shown``: as given)."""

    def __init__(self, path: Path, shown: str) -> None:
        self.path = path
        self.shown = shown

    def pending(self) -> PendingDir:
        return PendingDir(self)


def check_output_dir(path: str | Path, *, inputs: Sequence[str | Path] = ()) -> OutputDir:
    """Check that the folder ``path`` can be filled (an existing folder, or a new one in an existing folder),
    writing nothing; the symlink and ``-`` rules of :func:`check_output` apply.

    Raises:
        OutputError: the path is a file, FIFO or device, or where it goes does not accept new files.
    """
    target, shown = resolve(path)
    st = stat_or_none(target, shown)
    if st is None:
        check_parent(target.parent, shown)
    elif not stat.S_ISDIR(st.st_mode):
        check_inputs(st, shown, inputs)
        raise refuse(shown, f"it is {file_kind(st.st_mode)}: expected a directory (or a new one)")
    else:
        probe(target, shown)
    return OutputDir(target, shown)
