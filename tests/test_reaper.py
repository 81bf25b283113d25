"""The test harness's reaper (tests/support/reaper.py): what a test started dies with the test run, even when the run
is killed by SIGKILL and runs no ``finally``."""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from tests.support.reaper import MARK, alive

REPO = Path(__file__).resolve().parents[1]
DEADLINE_S = 10.0  # the reaper polls once a second; a loaded 2-core machine may delay it by a few more

# A stand-in for a pytest process: starts its reaper, then a station-like process in a session of its own (as the
# ROS helpers do) and a bash script whose background job is a grandchild (as the DDS helpers do); prints their pids.
OWNER = f"""
import os, subprocess, sys, time
sys.path.insert(0, {str(REPO)!r})
from tests.support import reaper
reaper.start(os.getpid())
station = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(300)"], start_new_session=True)
script = subprocess.Popen(["bash", "-c", "sleep 300 & echo $!; wait"], stdout=subprocess.PIPE, text=True,
                          start_new_session=True)
print(station.pid, script.pid, script.stdout.readline().strip(), flush=True)
time.sleep(300)
"""


def _gone_within(pids: list[int], seconds: float) -> list[int]:
    """The pids still alive after ``seconds``, or none as soon as all are gone."""
    end = time.monotonic() + seconds
    while True:
        left = [p for p in pids if alive(p)]
        if not left or time.monotonic() > end:
            return left
        time.sleep(0.2)


def test_what_a_killed_test_run_started_is_killed_with_it() -> None:
    env = {k: v for k, v in os.environ.items() if k != MARK}
    owner = subprocess.Popen([sys.executable, "-c", OWNER], env=env, stdout=subprocess.PIPE, text=True,
                             start_new_session=True)
    assert owner.stdout is not None
    pids = [int(p) for p in owner.stdout.readline().split()]
    try:
        assert len(pids) == 3 and _gone_within(pids, 1.0) == pids, "the owner's processes should be running"
        os.kill(owner.pid, signal.SIGKILL)  # no finally, no atexit
        owner.wait()
        assert _gone_within(pids, DEADLINE_S) == [], f"left running {DEADLINE_S} s after the test run died"
    finally:
        for pid in pids:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)


def test_the_suite_itself_is_marked() -> None:
    """This pytest process carries the mark, so what the tests start inherits it."""
    assert os.environ.get(MARK) == str(os.getpid())
