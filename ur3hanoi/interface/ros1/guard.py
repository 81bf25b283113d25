"""The keeper of a ``roscore`` the station starts: whatever happens to the station, no ROS process outlives it.

``python -m ur3hanoi.interface.ros1.guard LOG_DIR -- roscore -p PORT`` is started by
:class:`ur3hanoi.interface.ros1.master.RosCore` in its own session with a pipe on its standard input that only the
station holds. The guard

- becomes a child subreaper (``PR_SET_CHILD_SUBREAPER``): the nodes roscore launches (rosmaster, rosout; roslaunch
  puts each in its own session) are re-parented to the guard if roscore dies, so they can still be found;
- starts the command with ``ROS_LOG_DIR=LOG_DIR`` and ``PR_SET_PDEATHSIG`` = SIGTERM (a killed guard still stops
  roscore), its output appended to ``LOG_DIR/roscore.log``;
- prints ``pid N`` (the roscore's process id) and, if roscore exits by itself, ``exit CODE`` on its stdout;
- when its standard input reaches end of file -- the station closed it, or the kernel did because the station died,
  even by SIGKILL -- or on SIGTERM, stops roscore the way it wants to be stopped (SIGINT, twice), then SIGKILLs
  whatever of its process tree is left, removes ``LOG_DIR`` and exits.

The station's temporary folders are named :data:`LOG_DIR_PREFIX` + the station's pid; :func:`remove_stale_log_dirs`
removes those of stations that no longer run (a guard killed with SIGKILL cannot clean up).
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import select
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

LOG_DIR_PREFIX = "ur3hanoi-roscore-"
"""Temporary folder of one station's roscore logs: ``<tmp>/ur3hanoi-roscore-<station pid>-<random>``."""

_PR_SET_PDEATHSIG = 1
_PR_SET_CHILD_SUBREAPER = 36


def _prctl(option: int, value: int) -> None:
    libc = ctypes.CDLL(None, use_errno=True)
    libc.prctl(option, value, 0, 0, 0)


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


def _children() -> list[int]:
    pids: list[int] = []
    with contextlib.suppress(OSError):
        for task in Path(f"/proc/{os.getpid()}/task").iterdir():
            with contextlib.suppress(OSError):
                pids += [int(p) for p in (task / "children").read_text().split()]
    return pids


def _reap() -> None:
    with contextlib.suppress(ChildProcessError):
        while os.waitpid(-1, os.WNOHANG)[0] > 0:
            pass


def _wait(proc: subprocess.Popen[bytes], timeout_s: float) -> bool:
    with contextlib.suppress(subprocess.TimeoutExpired):
        proc.wait(timeout=timeout_s)
        return True
    return False


def stop_tree(proc: subprocess.Popen[bytes], sigint_timeout_s: float = 5.0) -> None:
    """SIGINT ``proc`` (twice: roscore misses one while it launches its nodes), then SIGKILL every process left
    among this (subreaper) process's children."""
    for wait_s in (sigint_timeout_s, 2.0 * sigint_timeout_s):
        if proc.poll() is not None:
            break
        with contextlib.suppress(ProcessLookupError):
            proc.send_signal(signal.SIGINT)
        if _wait(proc, wait_s):
            break
    deadline = time.monotonic() + 5.0
    while (left := _children()) and time.monotonic() < deadline:
        for pid in left:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        time.sleep(0.05)
        _reap()
        proc.poll()


class _TerminatedError(Exception):
    """SIGTERM: stop roscore and clean up as on end of file."""


def _stop_requested(_signum: int, _frame: object) -> None:
    raise _TerminatedError


def main(argv: list[str]) -> int:
    if len(argv) < 3 or argv[1] != "--":
        print("usage: python -m ur3hanoi.interface.ros1.guard LOG_DIR -- COMMAND...", file=sys.stderr)
        return 2
    log_dir, command = Path(argv[0]), argv[2:]
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the pipe stops the guard (a Ctrl-C reaches the station first)
    signal.signal(signal.SIGTERM, _stop_requested)  # so does a SIGTERM (system shutdown): cleanly
    _prctl(_PR_SET_CHILD_SUBREAPER, 1)
    parent = os.getppid()

    def child_setup() -> None:
        _prctl(_PR_SET_PDEATHSIG, signal.SIGTERM)

    env = dict(os.environ, ROS_LOG_DIR=str(log_dir))
    try:
        with open(log_dir / "roscore.log", "ab") as out:
            proc = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out, stderr=subprocess.STDOUT, env=env,
                                    start_new_session=True, preexec_fn=child_setup)  # single-threaded here
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
        signal.signal(signal.SIGTERM, signal.SIG_IGN)
        stop_tree(proc)
    finally:
        shutil.rmtree(log_dir, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
