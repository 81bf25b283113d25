"""Helpers of the ROS 2 tests: every process that starts a DDS participant runs inside a private network namespace
(``unshare -n``, loopback up with multicast), so no DDS packet can leave the machine, whatever the configuration.

:func:`in_netns` runs one shell script there (station and clients together, since a namespace lives as long as its
first process); the script's stdout/stderr and exit code come back. Tests skip, saying why, only where a namespace
cannot be made (no ``unshare``, or not permitted).
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]


def _netns_problem() -> str | None:
    if shutil.which("unshare") is None or shutil.which("ip") is None:
        return "unshare/ip not installed: cannot make a private network namespace for DDS"
    try:
        r = subprocess.run(["unshare", "-n", "sh", "-c", "ip link set lo up && ip link set lo multicast on"],
                           capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.TimeoutExpired) as exc:
        return f"unshare -n failed: {exc}"
    if r.returncode != 0:
        return f"unshare -n not permitted here ({r.stderr.strip()[:120]}): DDS tests need a private network namespace"
    return None


NETNS_PROBLEM = _netns_problem()
requires_netns = pytest.mark.skipif(NETNS_PROBLEM is not None, reason=NETNS_PROBLEM or "")

UR3HANOI = f"{sys.executable} -m ur3hanoi.cli"

PRELUDE = """set -u
ip link set lo up && ip link set lo multicast on
wait_ready() {  # wait_ready FILE: until the station printed its ready line (on its stderr; 60 s at most)
  for _ in $(seq 1 300); do grep -q "ros2-station: ready" "$1" && return 0; sleep 0.2; done
  echo "station not ready" >&2; cat "$1" >&2; return 1
}
written() {  # written REPORT: how many reports the station wrote (its reports_written; 0 before the first)
  "$UR3HANOI_PY" -c 'import json, sys
try: print(json.load(open(sys.argv[1]))["reports_written"])
except (OSError, ValueError, KeyError): print(0)' "$1"
}
snapshot() {  # snapshot PID REPORT COPY: SIGUSR1, then COPY the report once the station rewrote it (10 s at most)
  local n; n=$(written "$2"); kill -USR1 "$1"
  for _ in $(seq 1 200); do [ "$(written "$2")" -gt "$n" ] && { cp "$2" "$3"; return 0; }; sleep 0.05; done
  echo "no report within 10 s of SIGUSR1" >&2; return 1
}
report_until() {  # report_until PID REPORT COPY EXPR: snapshots until EXPR (Python, on the report r) holds (30 s)
  for _ in $(seq 1 60); do
    snapshot "$1" "$2" "$3" || return 1
    "$UR3HANOI_PY" -c 'import json, sys; r = json.load(open(sys.argv[1])); sys.exit(not eval(sys.argv[2]))' "$3" "$4" \
      && return 0
    sleep 0.5
  done
  echo "the report never had $4" >&2; return 1
}
"""


def in_netns(script: str, timeout: float, cwd: Path) -> subprocess.CompletedProcess[str]:
    """Run ``script`` (bash) in a new network namespace; ``$UR3HANOI`` is the CLI, ``$UR3HANOI_PY`` its Python; the
    PRELUDE's functions wait for what they can observe (a ready line, a report written). Killed after ``timeout``
    [s]."""
    env = dict(os.environ, UR3HANOI=UR3HANOI, UR3HANOI_PY=sys.executable, PYTHONUNBUFFERED="1", ROS_DOMAIN_ID="0")
    proc = subprocess.Popen(["unshare", "-n", "bash", "-c", PRELUDE + script], cwd=cwd, env=env, text=True,
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    try:
        out, err = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"netns script did not finish within {timeout} s:\n{out}\n{err}") from None
    finally:  # a station the script or client left in the background does not go on taking a core
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    return subprocess.CompletedProcess(proc.args, proc.returncode, out, err)
