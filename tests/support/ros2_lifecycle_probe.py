"""How ``ros2-station`` stops and restarts, measured from inside the tests' private network namespace (a helper
process of tests/interface/ros2/test_server.py: run it only through :func:`tests.ros2_support.in_netns`).

Usage: ``python tests/support/ros2_lifecycle_probe.py MODE DIR``; prints one JSON object.

- ``restart``: a station is SIGKILLed and another started at once on the same domain. Measures the seconds from the
  kill until the dead station's participant leaves the DDS graph (its ghost), and whether the new station
  publishes ``ur3e/position`` to a new node; then stops it with SIGTERM and measures how long that took.
- ``video``: a station rendering ``--video DIR/out.mp4`` (an old file there) is stopped by SIGINT: seconds to exit,
  exit code, whether the video changed, when its rendering process was gone; then another is SIGKILLed: whether the old
  video is unchanged, no temporary file is left, and its rendering process is gone (and how soon).
"""

from __future__ import annotations

import json
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant
from cyclonedds.core import InstanceState

from ur3hanoi.interface.ros2.dds import Ros2Node
from ur3hanoi.interface.ros2.msgs import PositionUR3e


def children(pid: int) -> set[int]:
    try:
        return {int(p) for p in Path(f"/proc/{pid}/task/{pid}/children").read_text().split()}
    except OSError:
        return set()


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def wait_for(predicate: Callable[[], bool], timeout_s: float) -> float | None:
    """Seconds until ``predicate()`` holds, None after ``timeout_s``."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if predicate():
            return time.monotonic() - t0
        time.sleep(0.01)
    return None


def start_station(folder: Path, name: str, *args: str) -> subprocess.Popen[str]:
    """A ros2-station started (stdout/stderr to files in ``folder``); :func:`ready` waits for it."""
    with open(folder / f"{name}.out", "w") as stdout, open(folder / f"{name}.err", "w") as stderr:
        return subprocess.Popen([sys.executable, "-m", "ur3hanoi.cli", "ros2-station", "--report",
                                 str(folder / f"{name}.json"), *args], stdout=stdout, stderr=stderr, text=True)


def ready(proc: subprocess.Popen[str], folder: Path, name: str) -> subprocess.Popen[str]:
    """``proc`` once its ready line is out."""
    out = folder / f"{name}.out"
    err = folder / f"{name}.err"  # the ready line is on stderr: stdout carries the JSON report alone
    if wait_for(lambda: "ros2-station: ready" in err.read_text() or proc.poll() is not None, 90.0) is None \
            or proc.poll() is not None:
        proc.kill()
        raise SystemExit(f"station {name} not ready: {out.read_text()} {(folder / f'{name}.err').read_text()}")
    return proc


def station(folder: Path, name: str, *args: str) -> subprocess.Popen[str]:
    """A ros2-station (stdout/stderr to files in ``folder``), once its ready line is out."""
    return ready(start_station(folder, name, *args), folder, name)


def stop(proc: subprocess.Popen[str], sig: signal.Signals) -> tuple[int, float]:
    """Send ``sig``; (exit code, seconds to exit)."""
    t0 = time.monotonic()
    proc.send_signal(sig)
    code = proc.wait(timeout=60)
    return code, time.monotonic() - t0


def restart(folder: Path) -> dict[str, Any]:
    node = Ros2Node("ur3hanoi_test_observer")  # the loopback configuration the station uses
    reader = BuiltinDataReader(node.participant, BuiltinTopicDcpsParticipant)
    positions = node.subscription("ur3e/position", PositionUR3e)
    me = str(node.participant.guid)
    live: dict[str, bool] = {}

    def others() -> set[str]:
        for s in reader.take(N=100):
            live[str(s.key)] = s.sample_info.instance_state == InstanceState.Alive
        return {k for k, up in live.items() if up and k != me}

    first = station(folder, "a")
    if wait_for(lambda: len(others()) == 1, 20.0) is None:
        raise SystemExit(f"the first station's participant not seen: {live}")
    (ghost,) = others()
    first.kill()
    t0 = time.monotonic()
    first.wait()
    second = start_station(folder, "b")  # watched while it starts: its start (seconds on a busy machine) is not the
    gone = wait_for(lambda: ghost not in others(), 30.0)  # ghost's time
    ghost_s = None if gone is None else time.monotonic() - t0
    ready(second, folder, "b")
    positions.take(N=1000)
    got = wait_for(lambda: bool(positions.take(N=10)), 5.0) is not None
    after = len(others())
    code, took = stop(second, signal.SIGTERM)
    return {"ghost_s": ghost_s, "others_after": after, "positions": got, "exit": code, "stop_s": took}


def video(folder: Path) -> dict[str, Any]:
    out = folder / "out.mp4"
    out.write_bytes(b"old video")
    first = station(folder, "a", "--video", str(out))
    renderers = children(first.pid)
    time.sleep(1.0)
    code, took = stop(first, signal.SIGINT)
    written = out.read_bytes() != b"old video" and out.stat().st_size > 1000
    gone_after = wait_for(lambda: not any(alive(p) for p in renderers), 10.0)
    first_gone_s = None if gone_after is None else took + gone_after  # from the SIGINT
    first_left = [p for p in renderers if alive(p)]
    out.write_bytes(b"old video")
    second = station(folder, "b", "--video", str(out))
    renderers_b = children(second.pid)
    time.sleep(1.0)
    second.kill()
    t0 = time.monotonic()
    second.wait()
    gone = wait_for(lambda: not any(alive(p) for p in renderers_b), 10.0)
    gone_s = None if gone is None else time.monotonic() - t0
    time.sleep(0.5)  # whatever the renderer would still write
    files = sorted(p.name for p in folder.iterdir() if p.name.startswith((".", "out")))
    return {"sigint_exit": code, "sigint_s": took, "sigint_written": written, "sigint_renderer_gone_s": first_gone_s,
            "sigint_left": first_left,
            "renderers": len(renderers_b), "renderer_gone_s": gone_s,
            "kept": out.read_bytes() == b"old video", "errors": (folder / "b.err").read_text()[-300:], "files": files}


def main() -> int:
    mode, folder = sys.argv[1], Path(sys.argv[2])
    print(json.dumps(restart(folder) if mode == "restart" else video(folder)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
