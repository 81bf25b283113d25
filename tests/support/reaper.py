"""Nothing a test starts outlives the test run, however the run ends.

The stations, masters and clients the tests start run in sessions of their own (so that a test can kill a whole
process group), and the tests stop them in ``finally`` blocks. A pytest killed by SIGKILL (a CI timeout, a terminal
closed, a tool that stops a job) runs no ``finally``: its stations would go on running their control loops, a core
each, for hours, and slow every later test on the wall clock. So every pytest process marks its environment with
``UR3HANOI_TEST_OWNER=<its pid>``, which all it starts inherits, and starts one reaper (this file, about 10 MB, waking
once a second): when the owner is gone, the reaper kills every process still carrying the mark, then exits.

A process started with an environment of its own (``env={...}`` not built from ``os.environ``) carries no mark; the
test helpers build theirs from ``os.environ``.

Run: ``python tests/support/reaper.py OWNER_PID``.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

MARK = "UR3HANOI_TEST_OWNER"
POLL_S = 1.0


def start(owner: int) -> subprocess.Popen[bytes]:
    """Mark this process's environment as ``owner``'s and start the reaper that watches ``owner``."""
    os.environ[MARK] = str(owner)
    env = {k: v for k, v in os.environ.items() if k != MARK}  # the reaper must not carry the mark it kills by
    return subprocess.Popen([sys.executable, str(Path(__file__).resolve()), str(owner)], env=env,
                            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            start_new_session=True)


def marked(owner: int) -> list[int]:
    """The pids whose environment carries ``owner``'s mark (processes of other users are not readable: skipped)."""
    needle = f"{MARK}={owner}".encode()
    found = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            environ = (entry / "environ").read_bytes()
        except OSError:  # gone meanwhile, or not ours
            continue
        if needle in environ.split(b"\0"):
            found.append(int(entry.name))
    return found


def alive(pid: int) -> bool:
    """True while ``pid`` exists and is not a zombie (a dead process its parent has not waited for yet)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def reap(owner: int) -> int:
    """Kill what carries ``owner``'s mark until nothing does (a dying shell may still start a child); how many."""
    killed: set[int] = set()
    for _ in range(5):
        pids = [p for p in marked(owner) if p != os.getpid()]
        if not pids:
            break
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
                killed.add(pid)
            except ProcessLookupError:
                pass
        time.sleep(0.1)
    return len(killed)


def main(argv: list[str]) -> int:
    owner = int(argv[0])
    while alive(owner):
        time.sleep(POLL_S)
    reap(owner)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
