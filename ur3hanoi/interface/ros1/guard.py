"""The keeper of a ``roscore`` the station starts: whatever happens to the station, no ROS process outlives it.

``python -m ur3hanoi.interface.ros1.guard LOG_DIR -- roscore -p PORT`` is started by
:class:`ur3hanoi.interface.ros1.master.RosCore` in its own session with a pipe on its standard input that only the
station holds. The guard

- becomes a child subreaper (``PR_SET_CHILD_SUBREAPER``): the nodes roscore launches (rosmaster, rosout; roslaunch
  puts each in its own session) are re-parented to the guard if roscore dies, so they can still be found;
- starts the command with ``ROS_LOG_DIR=LOG_DIR``, SIGINT and SIGTERM at their default actions (a child inherits
  ignored signals across ``exec``: a rosmaster that ignored SIGINT could only be SIGKILLed, 15 s later) and
  ``PR_SET_PDEATHSIG`` = SIGTERM (a killed guard still stops roscore), its output appended to ``LOG_DIR/roscore.log``
  (:func:`ur3hanoi.lifecycle.child_preexec`);
- prints ``pid N`` (the roscore's process id) and, if roscore exits by itself, ``exit CODE`` on its stdout;
- when its standard input reaches end of file -- the station closed it, or the kernel did because the station died,
  even by SIGKILL -- or on SIGINT or SIGTERM, stops roscore the way it wants to be stopped (SIGINT), SIGKILLs
  whatever of its process tree is left after :data:`STOP_GRACE_S`, removes ``LOG_DIR`` and exits: well within 2 s.

The station's temporary folders are named :data:`LOG_DIR_PREFIX` + the station's pid; :func:`remove_stale_log_dirs`
removes those of stations that no longer run (a guard killed with SIGKILL cannot clean up).
"""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ur3hanoi.lifecycle import PR_SET_CHILD_SUBREAPER, STOP_SIGNALS, child_preexec, prctl

LOG_DIR_PREFIX = "ur3hanoi-roscore-"
"""Temporary folder of one station's roscore logs: ``<tmp>/ur3hanoi-roscore-<station pid>-<random>``."""

STOP_GRACE_S = (1.0, 0.5)
"""How long [s] roscore gets after each of the two SIGINTs (it misses one that arrives while it launches its nodes)
before what is left of its tree is SIGKILLed: rosmaster stops in about 0.1 s, roscore with rosout in about 0.5 s."""


def make_log_dir() -> Path:
    """A new private temporary folder for a roscore's logs, named after this process (mode 0700)."""
    return Path(tempfile.mkdtemp(prefix=f"{LOG_DIR_PREFIX}{os.getpid()}-"))


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_stale_log_dirs(base: Path | None = None) -> list[Path]:
    """Remove this user's roscore log folders in ``base`` (default: the temporary folder) whose station is gone."""
    folder = Path(base if base is not None else tempfile.gettempdir())
    removed = []
    with contextlib.suppress(OSError):
        for path in folder.glob(f"{LOG_DIR_PREFIX}*"):
            try:
                pid = int(path.name.removeprefix(LOG_DIR_PREFIX).split("-")[0])
                st = path.lstat()
            except (ValueError, OSError):
                continue
            if path.is_dir() and not path.is_symlink() and st.st_uid == os.getuid() and not _alive(pid):
                shutil.rmtree(path, ignore_errors=True)
                removed.append(path)
    return removed


def _parent(pid: int) -> int | None:
    try:
        return int(Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[1])
    except (OSError, ValueError, IndexError):
        return None


def _guard_station(pid: int) -> int | None:
    """The station pid of guard process ``pid`` (named in its log folder argument), or None if it is no guard."""
    try:
        args = Path(f"/proc/{pid}/cmdline").read_bytes().decode(errors="replace").split("\0")
    except OSError:
        return None
    if __name__ not in args or "--" not in args:  # python -m ur3hanoi.interface.ros1.guard LOG_DIR -- COMMAND...
        return None
    folder = Path(args[args.index("--") - 1]).name
    try:
        return int(folder.removeprefix(LOG_DIR_PREFIX).split("-")[0]) if folder.startswith(LOG_DIR_PREFIX) else None
    except ValueError:
        return None


def orphaned(pid: int) -> bool:
    """True when process ``pid`` (a master) runs under a guard whose station is gone: the guard is stopping it.
    (A station started again on the same URI at once would otherwise attach to it and lose it a moment later.)"""
    parent = _parent(pid)
    for _ in range(3):  # rosmaster under the guard, or under roscore under the guard
        if parent is None or parent <= 1:
            return False
        station = _guard_station(parent)
        if station is not None:
            return _parent(parent) != station or not _alive(station)
        parent = _parent(parent)
    return False


def _children(pid: int | None = None) -> list[int]:
    """The children of process ``pid`` (default: this one)."""
    pids: list[int] = []
    with contextlib.suppress(OSError):
        for task in Path(f"/proc/{os.getpid() if pid is None else pid}/task").iterdir():
            with contextlib.suppress(OSError):
                pids += [int(p) for p in (task / "children").read_text().split()]
    return pids


def _tree(pid: int) -> list[int]:
    """``pid`` and every process below it."""
    found, todo = [], [pid]
    while todo:
        p = todo.pop()
        found.append(p)
        todo += [c for c in _children(p) if c not in found]
    return found


def _reap() -> None:
    with contextlib.suppress(ChildProcessError):
        while os.waitpid(-1, os.WNOHANG)[0] > 0:
            pass


def _wait(proc: subprocess.Popen[bytes], timeout_s: float) -> bool:
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=timeout_s)
        return True
    return False


def stop_tree(proc: subprocess.Popen[bytes], grace_s: tuple[float, ...] = STOP_GRACE_S) -> None:
    """SIGINT ``proc`` and every process below it, all at once (roscore's nodes then stop together instead of one
    after the other), once per entry of ``grace_s``, waiting that long [s] after each; then SIGKILL every process
    left among this (subreaper) process's children."""
    for wait_s in grace_s:
        if proc.poll() is not None:
            break
        for pid in _tree(proc.pid):
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGINT)
        if _wait(proc, wait_s):
            break
    deadline = time.monotonic() + 5.0
    while (left := _children()) and time.monotonic() < deadline:
        for pid in left:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        time.sleep(0.02)
        _reap()
        proc.poll()


class _TerminatedError(Exception):
    """SIGINT or SIGTERM: stop roscore and clean up as on end of file."""


def _stop_requested(_signum: int, _frame: object) -> None:
    raise _TerminatedError


def main(argv: list[str]) -> int:
    if len(argv) < 3 or argv[1] != "--":
        print("usage: python -m ur3hanoi.interface.ros1.guard LOG_DIR -- COMMAND...", file=sys.stderr)
        return 2
    log_dir, command = Path(argv[0]), argv[2:]
    # The pipe stops the guard; so do SIGINT and SIGTERM (a system shutdown), cleanly. Handled, not ignored: the
    # command must not inherit an ignored SIGINT (child_preexec resets both anyway).
    for s in STOP_SIGNALS:
        signal.signal(s, _stop_requested)
    prctl(PR_SET_CHILD_SUBREAPER, 1)
    parent = os.getppid()
    env = dict(os.environ, ROS_LOG_DIR=str(log_dir))
    try:
        with open(log_dir / "roscore.log", "ab") as out:
            proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, env=env,
                                    start_new_session=True, preexec_fn=child_preexec())  # single-threaded here
        print(f"pid {proc.pid}", flush=True)
        reported = False
        with contextlib.suppress(_TerminatedError):
            while True:
                ready, _, _ = select.select([sys.stdin], [], [], 0.2)
                if ready and not os.read(sys.stdin.fileno(), 4096):
                    break  # end of file: the station closed the pipe or died
                if os.getppid() != parent:
                    break  # re-parented: the station is gone (belt and braces for the pipe)
                if not reported and proc.poll() is not None:
                    reported = True
                    with contextlib.suppress(OSError):
                        print(f"exit {proc.returncode}", flush=True)
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_IGN)  # stopping now: a second signal must not cut it short
        stop_tree(proc)
    finally:
        shutil.rmtree(log_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
