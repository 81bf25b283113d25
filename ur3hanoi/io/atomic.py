"""The one writer of ur3hanoi: output paths checked first, atomic replacement, a lock for read-modify-write.

Every output (lab tables, calibrations, plan CSVs, reports, videos, frame folders) goes through this module:
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
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import hashlib
import os
import pwd
import re
import secrets
import shutil
import stat
import time
from collections.abc import Iterator, Sequence
from pathlib import Path

from ur3hanoi.errors import OutputError, printable
from ur3hanoi.io.reading import file_kind

LOCK_TIMEOUT_S = 60.0
"""Longest wait [s] for another writer of the same file before giving up."""

ANONYMOUS_TEMPORARIES = True
"""Write text through an unnamed ``O_TMPFILE`` first (False: always a named temporary; for tests)."""

TEMP_PREFIX = ".ur3hanoi-"
"""Start of every temporary and lock file name this module creates."""

_TEMP_NAME = re.compile(r"\.ur3hanoi-(\d{1,10})-([0-9a-f]{8})-[0-9a-f]{8}\.[0-9A-Za-z]{1,8}")
_LOCK_NAME = re.compile(r"\.ur3hanoi-[0-9a-f]{16}\.lock")
_NO_TMPFILE = {errno.EOPNOTSUPP, errno.EISDIR, errno.EINVAL}  # O_TMPFILE unsupported (not "not allowed")
_MAX_LINKS = 40  # the kernel's limit of symlinks followed in one path (ELOOP beyond)


def _refuse(shown: str, problem: str) -> OutputError:
    return OutputError(f"cannot write {printable(shown)}: {problem}")


def _user(uid: int) -> str:
    try:
        return f"user {pwd.getpwuid(uid).pw_name!r} (uid {uid})"
    except KeyError:
        return f"uid {uid}"


# ------------------------------------------------------------------------------------------ temporary names


def _host_tag() -> str:
    return hashlib.sha256(os.uname().nodename.encode("utf-8", "surrogateescape")).hexdigest()[:8]


def temporary_name(suffix: str = ".tmp") -> str:
    """A fresh temporary name ``.ur3hanoi-<pid>-<host>-<random><suffix>`` (under 50 bytes, whatever the target)."""
    return f"{TEMP_PREFIX}{os.getpid()}-{_host_tag()}-{secrets.token_hex(4)}{suffix}"


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
        if _same_file(os.fstat(fd), os.stat(path, follow_symlinks=False)):
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


# ------------------------------------------------------------------------------------------------ the path


def _same_file(a: os.stat_result, b: os.stat_result) -> bool:
    return (a.st_dev, a.st_ino) == (b.st_dev, b.st_ino)


def _check_link(directory: str, link: str, link_st: os.stat_result, shown: str) -> None:
    """The kernel's ``protected_symlinks`` rule: in a sticky world-writable directory, follow only a link owned by
    the directory's owner or by the caller."""
    dir_st = os.stat(directory)
    if not (dir_st.st_mode & stat.S_ISVTX and dir_st.st_mode & stat.S_IWOTH):
        return
    if link_st.st_uid in (dir_st.st_uid, os.geteuid()):
        return
    raise _refuse(shown, f"{printable(link)} is a symbolic link of {_user(link_st.st_uid)} in the shared sticky "
                         f"directory {printable(directory)}: not followed (the kernel's protected_symlinks rule); "
                         "remove the link or choose another path")


def _resolve(path: str | Path) -> tuple[Path, str]:
    """The absolute file a path names, every symlink on the way followed under :func:`_check_link`."""
    shown = str(path)
    if not shown:
        raise _refuse("''", "the path is empty")
    if "\0" in shown:
        raise _refuse(shown, "the path contains a NUL character")
    if shown == "-":
        raise _refuse(shown, "standard output is not supported for this output: give a file name (./- for a file "
                             "named '-')")
    current = "/" if shown.startswith("/") else os.getcwd()
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
                raise _refuse(shown, os.strerror(errno.ELOOP))
            _check_link(current, candidate, st, shown)
            target = os.readlink(candidate)
            if target.startswith("/"):
                current = "/"
            parts.extend(reversed(target.split("/")))
            continue
        current = candidate
    return Path(current), shown


def _probe(directory: Path, shown: str) -> None:
    """Refuse a directory that does not accept a new file, creating none (an unnamed O_TMPFILE where supported)."""
    try:
        fd = os.open(directory, os.O_TMPFILE | os.O_WRONLY | os.O_CLOEXEC, 0o600)
    except OSError as exc:
        if exc.errno not in _NO_TMPFILE:
            raise _refuse(shown, f"the directory {printable(directory)} is not writable ({exc.strerror})") from None
        probe = directory / temporary_name(".probe")
        try:
            fd = os.open(probe, os.O_CREAT | os.O_EXCL | os.O_WRONLY | os.O_CLOEXEC | os.O_NOFOLLOW, 0o600)
        except OSError as exc2:
            raise _refuse(shown, f"the directory {printable(directory)} does not accept new files "
                                 f"({exc2.strerror})") from None
        with contextlib.suppress(OSError):
            os.unlink(probe)
    os.close(fd)


def _check_parent(parent: Path, shown: str) -> None:
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
    _probe(parent, shown)


def _stat_or_none(target: Path, shown: str) -> os.stat_result | None:
    try:
        return os.stat(target)
    except FileNotFoundError:
        return None
    except OSError as exc:
        raise _refuse(shown, exc.strerror or str(exc)) from None


def _check_inputs(st: os.stat_result, shown: str, inputs: Sequence[str | Path]) -> None:
    for src in inputs:
        try:
            same = _same_file(st, os.stat(src))
        except (OSError, ValueError):
            continue
        if same:
            raise _refuse(shown, f"it is also an input of this command ({printable(src)}): choose another "
                                 "output file")


def _check(target: Path, shown: str, inputs: Sequence[str | Path]) -> None:
    st = _stat_or_none(target, shown)
    if st is not None:
        if not stat.S_ISREG(st.st_mode):
            raise _refuse(shown, f"it is {file_kind(st.st_mode)}: expected a regular file (or a new one)")
        _check_inputs(st, shown, inputs)
    _check_parent(target.parent, shown)


# ------------------------------------------------------------------------------------------------ writing


def _fsync_dir(directory: Path | int) -> None:
    """Make a rename durable (best effort: some filesystems refuse to fsync a directory)."""
    with contextlib.suppress(OSError):
        fd = directory if isinstance(directory, int) else os.open(directory, os.O_RDONLY | os.O_DIRECTORY |
                                                                  os.O_CLOEXEC)
        try:
            os.fsync(fd)
        finally:
            if not isinstance(directory, int):
                os.close(fd)


def _existing_mode(path: Path) -> int | None:
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
        if exc.errno in _NO_TMPFILE:
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
    _fsync_dir(dfd)


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
            raise _refuse(out.shown, f"{exc.strerror} (in {printable(out.path.parent)})") from None

    def commit(self) -> Path:
        """Rename the temporary over the target (an existing target keeps its permissions); returns the target."""
        try:
            mode = _existing_mode(self.out.path)
            if mode is not None:
                os.chmod(self.path, mode)
            os.replace(self.path, self.out.path)
        except OSError as exc:
            self.discard()
            raise _refuse(self.out.shown, f"{exc.strerror or exc}; nothing was written") from None
        _fsync_dir(self.out.path.parent)
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

    def write(self, text: str | bytes) -> None:
        """Replace the file with ``text`` (UTF-8) atomically; see the module docstring."""
        data = text.encode("utf-8") if isinstance(text, str) else bytes(text)
        parent = self.path.parent
        remove_stale_temporaries(parent)
        try:
            dfd = os.open(parent, os.O_RDONLY | os.O_DIRECTORY | os.O_CLOEXEC)
        except OSError as exc:
            raise _refuse(self.shown, f"{exc.strerror} (in {printable(parent)})") from None
        try:
            _write_in(dfd, self.path.name, data, _existing_mode(self.path))
        except OSError as exc:
            raise _refuse(self.shown, f"{exc.strerror or exc}; nothing was written") from None
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
    target, shown = _resolve(path)
    _check(target, shown, inputs)
    return Output(target, shown)


# ------------------------------------------------------------------------------------------------ folders


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
            raise _refuse(out.shown, f"{exc.strerror} (in {printable(host)})") from None

    def commit(self, replaces: re.Pattern[str] | None = None) -> Path:
        """Move the files into the folder; files of the folder matching ``replaces`` (a previous run's) that this
        run did not write are removed. Returns the folder."""
        target = self.out.path
        try:
            if self.path.parent != target:  # a new folder: one rename
                try:
                    os.rename(self.path, target)
                    _fsync_dir(target.parent)
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
            raise _refuse(self.out.shown, f"{exc.strerror or exc}") from None
        _fsync_dir(target)
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
    target, shown = _resolve(path)
    st = _stat_or_none(target, shown)
    if st is None:
        _check_parent(target.parent, shown)
    elif not stat.S_ISDIR(st.st_mode):
        _check_inputs(st, shown, inputs)
        raise _refuse(shown, f"it is {file_kind(st.st_mode)}: expected a directory (or a new one)")
    else:
        _probe(target, shown)
    return OutputDir(target, shown)


# ------------------------------------------------------------------------------------------------ the lock


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


def _foreign_lock(shown: str, lock_path: Path, uid: int) -> OutputError:
    return _refuse(shown, f"the lock file {printable(lock_path)} belongs to {_user(uid)}, not to you: another user "
                          "is writing this file (remove the lock file if they are not)")


def _open_lock(lock_path: Path, shown: str) -> int:
    try:
        fd = os.open(lock_path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC | os.O_NOFOLLOW | os.O_NONBLOCK, 0o600)
    except OSError as exc:
        with contextlib.suppress(OSError):
            uid = os.lstat(lock_path).st_uid
            if uid != os.geteuid():
                raise _foreign_lock(shown, lock_path, uid) from None
        raise _refuse(shown, f"cannot create the lock file {printable(lock_path)} ({exc.strerror})") from None
    uid = os.fstat(fd).st_uid
    if uid != os.geteuid():
        os.close(fd)
        raise _foreign_lock(shown, lock_path, uid)
    return fd


@contextlib.contextmanager
def _file_lock(target: Path, shown: str) -> Iterator[None]:
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
