"""The one writer of ur3hanoi: output paths checked first, atomic replacement, a lock for read-modify-write.

Every output (lab tables, calibrations, plan CSVs, reports, videos, frame folders) goes through this package:
:func:`atomic_write` or :func:`locked_output` for text, :meth:`Output.pending` for a file another program writes
(ffmpeg), :func:`check_output_dir` and :meth:`OutputDir.pending` for a folder of frames.

- The path is checked before anything is written: ``-`` (standard output) is refused here (a command that means
  stdout by it handles it first); it must not be an input of the same command, a directory, a FIFO, socket or
  device; its directory must exist and really accept a new file (probed with an unnamed ``O_TMPFILE``, so a
  read-only file system, ``/proc`` or a missing folder is refused before any work). A refused path raises
  :class:`~ur3hanoi.errors.OutputError` naming it, in one line.
- A symlink is written through (its target is replaced, the link stays, as editors do), but only where the kernel's
  ``protected_symlinks`` rule would follow it: a link in a sticky world-writable directory (``/tmp``) is followed
  only when its owner is the directory's owner or the caller (effective uid). A link planted there by another user
  is refused, whatever ``/proc/sys/fs/protected_symlinks`` says.
- Text goes to an unnamed temporary file (``O_TMPFILE``) in the target's directory, is flushed to disk, gets a
  short name (``.ur3hanoi-<pid>-<host>-<random>.tmp``, ``linkat`` via ``/proc/self/fd``) and is renamed over the
  target. Where ``O_TMPFILE`` or ``/proc`` is missing, the temporary is created under that name directly. A failure
  (a full disk included) removes it and leaves an existing target byte-identical. A new file gets the usual
  permissions (0666 less the umask), an existing one keeps its own.
- Temporary names hold the writer's pid and a hash of the host name and never depend on the target's name (a
  255-byte file name works). A writer killed by SIGKILL can leave one behind: every later write into that
  directory removes the temporaries (and unlocked lock files) of this user and host whose process is gone.
- :func:`locked_output` holds an exclusive ``fcntl.flock`` on a lock file beside the target
  (``.ur3hanoi-<hash of the name>.lock``) while the caller reads the old file and writes the new one, so
  concurrent writers of one file never lose each other's updates. The lock file is removed when the lock is
  released. A lock file owned by another user is refused at once, naming its owner.

Modules: :mod:`~ur3hanoi.io.atomic.temporaries` (temporary and lock names, stale ones removed),
:mod:`~ur3hanoi.io.atomic.paths` (the checks), :mod:`~ur3hanoi.io.atomic.files` (a file),
:mod:`~ur3hanoi.io.atomic.folders` (a folder), :mod:`~ur3hanoi.io.atomic.lock` (read-modify-write).
"""

from __future__ import annotations

from ur3hanoi.io.atomic.files import Output, PendingFile, check_output
from ur3hanoi.io.atomic.folders import OutputDir, PendingDir, check_output_dir
from ur3hanoi.io.atomic.lock import LOCK_TIMEOUT_S, atomic_write, locked_output
from ur3hanoi.io.atomic.temporaries import TEMP_PREFIX, lock_file_name, remove_stale_temporaries, temporary_name

__all__ = [
    "LOCK_TIMEOUT_S",
    "TEMP_PREFIX",
    "Output",
    "OutputDir",
    "PendingDir",
    "PendingFile",
    "atomic_write",
    "check_output",
    "check_output_dir",
    "lock_file_name",
    "locked_output",
    "remove_stale_temporaries",
    "temporary_name",
]
