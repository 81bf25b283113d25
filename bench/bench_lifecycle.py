#!/usr/bin/env python3
"""Benchmark how the stations stop: SIGINT, SIGTERM, SIGKILL and a restart right after a SIGKILL, ROS 1 and ROS 2.

Usage: .venv/bin/python bench/bench_lifecycle.py [--source DIR] [--only ros1|ros2] [--repeat N]

ROS 1 (``ros-station`` starting its own master on a free port of 127.0.0.1):
- SIGINT / SIGTERM: seconds from the signal to the station's exit, and to the moment every process it started
  (the roscore guard, rosmaster) is gone and no master answers on the port;
- SIGKILL of the station alone: seconds until every process it started is gone and the port is free;
- restart: SIGKILL a station, start another on the same URI at once; seconds until the new one is ready, and
  whether it still has a master once the old station's processes are gone (the old code attached to the dying
  master and lost it ~15 s later).
ROS 2 (``ros2-station`` inside a private network namespace, ``unshare -n``, as the tests run DDS):
- SIGINT / SIGTERM: seconds to exit; SIGKILL: seconds until the process is gone;
- restart: SIGKILL a station, start another on the same domain at once; seconds until it is ready, and how long
  the dead station's participant stays in the DDS graph after the kill (a ghost, until its lease ends).

``--source DIR`` runs the commands of another checkout (e.g. the code before a change: ``git archive``); the
figures are wall-clock times on a shared machine: each is the median of ``--repeat`` runs (default 3).
Needs Debian's ROS 1 (tools/ensure-system-deps.sh) and ``unshare -n``: about 2-4 minutes.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[1]
TIMEOUT_S = 40.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def port_free(port: int) -> bool:
    """Nothing listens on 127.0.0.1:port (a connection is refused)."""
    with socket.socket() as s:
        s.settimeout(0.5)
        return s.connect_ex(("127.0.0.1", port)) != 0


def alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def descendants(pid: int) -> set[int]:
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                parents[int(entry.name)] = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
            except OSError:
                continue
    found: set[int] = set()
    todo = [pid]
    while todo:
        parent = todo.pop()
        kids = [c for c, pp in parents.items() if pp == parent and c not in found]
        found.update(kids)
        todo += kids
    return found


def wait_for(predicate: Callable[[], bool], timeout_s: float = TIMEOUT_S, step_s: float = 0.01) -> float | None:
    """Seconds until ``predicate()`` holds, None after ``timeout_s``."""
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout_s:
        if predicate():
            return time.monotonic() - t0
        time.sleep(step_s)
    return None


class Proc:
    """A station subprocess in its own session; its output lines are collected, ``ready`` set on its ready line."""

    def __init__(self, cmd: list[str], env: dict[str, str], ready_word: str) -> None:
        # Run in the source folder: ``python -m`` puts the working folder first on the path, before PYTHONPATH.
        self.proc = subprocess.Popen(cmd, env=env, text=True, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, start_new_session=True, cwd=env["PYTHONPATH"])
        self.lines: list[str] = []
        self.ready = threading.Event()
        for stream in (self.proc.stdout, self.proc.stderr):
            threading.Thread(target=self._pump, args=(stream, ready_word), daemon=True).start()

    def _pump(self, stream: Any, ready_word: str) -> None:
        for line in stream:
            self.lines.append(line)
            if ready_word in line:
                self.ready.set()

    def wait_ready(self) -> float:
        t0 = time.monotonic()
        if wait_for(lambda: self.ready.is_set() or self.proc.poll() is not None, 90.0) is None or \
                not self.ready.is_set():
            raise SystemExit(f"station not ready:\n{''.join(self.lines)}")
        return time.monotonic() - t0

    def kill_all(self) -> None:
        for pid in [self.proc.pid, *descendants(self.proc.pid)]:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        with contextlib.suppress(subprocess.TimeoutExpired):
            self.proc.wait(5)


def cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "ur3hanoi.cli", *args]


def base_env(source: Path, tmp: Path) -> dict[str, str]:
    return dict(os.environ, PYTHONPATH=str(source), PYTHONUNBUFFERED="1", TMPDIR=str(tmp),
                ROS_HOME=str(tmp / "ros_home"))


# ---------------------------------------------------------------------------------------------------------- ROS 1


def stop_timed(st: Proc, sig: signal.Signals, also_gone: Callable[[], bool] = lambda: True) -> dict[str, float | None]:
    """Send ``sig`` to a ready station: how long until it exits (None for SIGKILL) and until it and every process
    it started are gone (and ``also_gone()``), in seconds from the signal."""
    st.wait_ready()
    below = descendants(st.proc.pid)
    t0 = time.monotonic()
    os.kill(st.proc.pid, sig)
    exit_s = None if sig == signal.SIGKILL else wait_for(lambda: st.proc.poll() is not None)
    clean = wait_for(lambda: st.proc.poll() is not None and not any(alive(p) for p in below) and also_gone())
    return {"exit_s": exit_s, "clean_s": None if clean is None else time.monotonic() - t0}


def ros1_stop(source: Path, tmp: Path, sig: signal.Signals) -> dict[str, float | None]:
    """Exit time and clean-up time [s] of a station with its own master after ``sig``."""
    port = free_port()
    env = dict(base_env(source, tmp), ROS_MASTER_URI=f"http://127.0.0.1:{port}")
    st = Proc(cli("ros-station", "--report", str(tmp / f"r{port}.json")), env, "ros-station: ready")
    try:
        return stop_timed(st, sig, lambda: port_free(port))
    finally:
        st.kill_all()


def ros1_restart(source: Path, tmp: Path) -> dict[str, Any]:
    """SIGKILL a station, start another on the same URI at once: seconds until the old one's processes are gone
    (from the kill), until the new one is ready, and whether it keeps a master."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    env = dict(base_env(source, tmp), ROS_MASTER_URI=uri)
    first = Proc(cli("ros-station", "--report", str(tmp / f"a{port}.json")), env, "ros-station: ready")
    second: Proc | None = None
    try:
        first.wait_ready()
        below = descendants(first.proc.pid)
        os.kill(first.proc.pid, signal.SIGKILL)
        t0 = time.monotonic()
        gone: list[float] = []
        watcher = threading.Thread(target=lambda: wait_for(lambda: not any(alive(p) for p in below)) is not None
                                   and gone.append(time.monotonic() - t0))
        watcher.start()
        second = Proc(cli("ros-station", "--report", str(tmp / f"b{port}.json")), env, "ros-station: ready")
        ready_s = second.wait_ready()
        watcher.join()
        old_gone = gone[0] if gone else None
        time.sleep(1.0)
        sys.path.insert(0, str(source))
        from ur3hanoi.interface.ros1.master import node_registered

        kept = second.proc.poll() is None and node_registered(uri, "/ur3hanoi_station")
        return {"ready_s": ready_s, "old_gone_s": old_gone, "kept": kept}
    finally:
        first.kill_all()
        if second is not None:
            second.kill_all()


# ---------------------------------------------------------------------------------------------------------- ROS 2


def ros2_station(source: Path, tmp: Path, name: str) -> Proc:
    env = dict(base_env(source, tmp), ROS_DOMAIN_ID="0")
    return Proc(cli("ros2-station", "--report", str(tmp / f"{name}.json")), env, "ros2-station: ready")


def ros2_stop(source: Path, tmp: Path, sig: signal.Signals) -> dict[str, float | None]:
    st = ros2_station(source, tmp, f"s{sig.value}-{time.monotonic_ns()}")
    try:
        return stop_timed(st, sig)
    finally:
        st.kill_all()


def ros2_restart(source: Path, tmp: Path) -> dict[str, Any]:
    """SIGKILL a station and start another at once; how long the dead one's participant stays in the graph."""
    sys.path.insert(0, str(source))
    from cyclonedds.builtin import BuiltinDataReader, BuiltinTopicDcpsParticipant
    from cyclonedds.core import InstanceState
    from cyclonedds.domain import Domain, DomainParticipant

    from ur3hanoi.interface.ros2.dds import cyclone_config

    domain = Domain(0, cyclone_config())
    participant = DomainParticipant(0)
    reader = BuiltinDataReader(participant, BuiltinTopicDcpsParticipant)
    states: dict[str, bool] = {}

    def others() -> int:
        for s in reader.take(N=100):
            states[str(s.key)] = s.sample_info.instance_state == InstanceState.Alive
        return sum(states.values()) - 1  # not this observer

    first = ros2_station(source, tmp, f"a{time.monotonic_ns()}")
    second: Proc | None = None
    try:
        first.wait_ready()
        wait_for(lambda: others() == 1, 10.0)
        t0 = time.monotonic()
        os.kill(first.proc.pid, signal.SIGKILL)
        second = ros2_station(source, tmp, f"b{time.monotonic_ns()}")
        ready_s = second.wait_ready()
        one = wait_for(lambda: others() == 1 and second.proc.poll() is None, 30.0)
        return {"ready_s": ready_s, "ghost_s": None if one is None else time.monotonic() - t0,
                "works": second.proc.poll() is None}
    finally:
        first.kill_all()
        if second is not None:
            second.kill_all()
        del domain  # kept until here: the observer's participant uses its configuration


def ros2_inner(source: Path, repeat: int) -> dict[str, Any]:
    subprocess.run(["ip", "link", "set", "lo", "up"], check=True)
    subprocess.run(["ip", "link", "set", "lo", "multicast", "on"], check=True)
    with tempfile.TemporaryDirectory() as t:
        tmp = Path(t)
        out: dict[str, Any] = {}
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            out[sig.name] = [ros2_stop(source, tmp, sig) for _ in range(repeat)]
        out["restart"] = [ros2_restart(source, tmp) for _ in range(repeat)]
        return out


# ---------------------------------------------------------------------------------------------------------- table


def median(runs: list[dict[str, Any]], key: str) -> str:
    values = [r[key] for r in runs]
    if any(v is None for v in values):
        return f"> {TIMEOUT_S:g} s"
    if isinstance(values[0], bool):
        return f"{sum(values)}/{len(values)}"
    return f"{statistics.median(values):.2f} s"


def table(ros1: dict[str, Any] | None, ros2: dict[str, Any] | None) -> str:
    rows = ["| middleware | event | station exits | everything it started gone | restart: ready | restart: kept |",
            "|---|---|---|---|---|---|"]
    for name, res in (("ROS 1", ros1), ("ROS 2", ros2)):
        if res is None:
            continue
        for sig in ("SIGINT", "SIGTERM"):
            rows.append(f"| {name} | {sig} | {median(res[sig], 'exit_s')} | {median(res[sig], 'clean_s')} | | |")
        rows.append(f"| {name} | SIGKILL | (killed) | {median(res['SIGKILL'], 'clean_s')} | | |")
        r = res["restart"]
        if name == "ROS 1":
            rows.append(f"| {name} | restart after SIGKILL | | old master gone {median(r, 'old_gone_s')} after the "
                        f"kill | {median(r, 'ready_s')} | master kept {median(r, 'kept')} |")
        else:
            rows.append(f"| {name} | restart after SIGKILL | | ghost participant gone {median(r, 'ghost_s')} after "
                        f"the kill | {median(r, 'ready_s')} | works {median(r, 'works')} |")
    return "\n".join(rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--source", type=Path, default=REPO, help="checkout whose ur3hanoi runs (default: this one)")
    parser.add_argument("--only", choices=["ros1", "ros2"])
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--ros2-inner", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    source = args.source.resolve()
    if args.ros2_inner:
        print(json.dumps(ros2_inner(source, args.repeat)))
        return 0
    ros1 = ros2 = None
    if args.only != "ros2":
        with tempfile.TemporaryDirectory() as t:
            tmp = Path(t)
            ros1 = {sig.name: [ros1_stop(source, tmp, sig) for _ in range(args.repeat)]
                    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL)}
            ros1["restart"] = [ros1_restart(source, tmp) for _ in range(args.repeat)]
    if args.only != "ros1":
        inner = subprocess.run(["unshare", "-n", sys.executable, __file__, "--ros2-inner", "--source", str(source),
                                "--repeat", str(args.repeat)], capture_output=True, text=True, timeout=1800)
        if inner.returncode != 0:
            raise SystemExit(f"the ROS 2 part failed:\n{inner.stderr[-3000:]}")
        ros2 = json.loads(inner.stdout.strip().splitlines()[-1])
    print(f"stations stopping ({source}, median of {args.repeat})")
    print(table(ros1, ros2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
