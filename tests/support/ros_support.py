"""Helpers of the ROS tests: a private roscore per test, ros-station as a subprocess, bounded waits.

Every test gets its own master port (``roscore -p PORT``, ``ROS_MASTER_URI=http://127.0.0.1:PORT``) and its own
ROS_HOME (logs) under tmp_path, and everything started is stopped in ``finally`` blocks, killed if it does not
stop in time. ROS tests are marked ``ros`` (``pytest -m ros``); they are skipped when Debian's ROS packages are
missing, except under CI (CI installs them with tools/ensure-system-deps.sh, so there a missing ROS fails).
"""

from __future__ import annotations

import contextlib
import itertools
import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import pytest

from ur3hanoi.interface.ros1.env import ROS_PYTHON_DIR

ROS_INSTALLED = shutil.which("roscore") is not None and (ROS_PYTHON_DIR / "rospy" / "__init__.py").is_file()

requires_ros = pytest.mark.skipif(not ROS_INSTALLED and not os.environ.get("CI"),
                                  reason="ROS 1 not installed (run tools/ensure-system-deps.sh as root)")

START_TIMEOUT_S = 60.0
STOP_TIMEOUT_S = 20.0


PORT_FLOOR = 20000
"""The lowest port :func:`free_port` gives; it gives ports below the kernel's ephemeral range."""
_ports_given = itertools.count()


def _ephemeral_low() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 0


def free_port() -> int:
    """A TCP port free on 127.0.0.1 now, for a test's master. A port from ``bind(0)`` lies in the ephemeral range,
    where any process's next connection or server (another test's node, side by side under ``make test``) may take
    it before the master binds it; a port below that range is only taken by someone asking for it by number. Each
    process walks the ports from a start of its own (by pid), so that tests side by side ask for different ones."""
    span = _ephemeral_low() - PORT_FLOOR
    for _ in range(max(span, 0)):
        port = PORT_FLOOR + (os.getpid() * 97 + next(_ports_given)) % span
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:  # in use, or still in TIME_WAIT
                continue
            return port
    with socket.socket() as s:  # no room below the ephemeral range on this machine
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def ros_env(port: int, tmp_path: Path) -> dict[str, str]:
    """Environment of every process of one test: its master, its log folder, loopback addresses."""
    home = tmp_path / "ros_home"
    home.mkdir(exist_ok=True)
    return dict(os.environ, ROS_MASTER_URI=f"http://127.0.0.1:{port}", ROS_HOME=str(home), ROS_IP="127.0.0.1",
                PYTHONUNBUFFERED="1")


def ur3hanoi_cmd(*args: str) -> list[str]:
    return [sys.executable, "-m", "ur3hanoi.cli", *args]


class Station:
    """A running ``ur3hanoi ros-station`` subprocess; stdout/stderr collected in the background."""

    def __init__(self, proc: subprocess.Popen[str], report: Path) -> None:
        self.proc = proc
        self.report_path = report
        self.stdout: list[str] = []
        self.stderr: list[str] = []
        self._ready = threading.Event()
        self._threads = [threading.Thread(target=self._pump, args=(proc.stdout, self.stdout, True), daemon=True),
                         threading.Thread(target=self._pump, args=(proc.stderr, self.stderr, True), daemon=True)]
        for t in self._threads:
            t.start()

    def _pump(self, stream: Any, lines: list[str], watch_ready: bool) -> None:
        for line in stream:
            lines.append(line)
            if watch_ready and line.startswith("ur3hanoi ros-station: ready"):
                self._ready.set()

    def wait_ready(self, timeout: float = START_TIMEOUT_S) -> None:
        deadline = time.monotonic() + timeout
        while not self._ready.wait(0.1):
            if self.proc.poll() is not None or time.monotonic() > deadline:
                raise AssertionError(f"ros-station not ready (exit {self.proc.poll()}):\n{self.log()}")

    def log(self) -> str:
        return "".join(self.stdout) + "".join(self.stderr)

    def snapshot(self, timeout: float = 10.0) -> dict[str, Any]:
        """Ask for a report (SIGUSR1) and return it once written."""
        before = self._written()
        self.proc.send_signal(signal.SIGUSR1)
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if self._written() > before:
                return self.read_report()
            time.sleep(0.05)
        raise AssertionError(f"no report after SIGUSR1 within {timeout} s:\n{self.log()}")

    def _written(self) -> int:
        try:
            return int(self.read_report()["reports_written"])
        except (OSError, ValueError, KeyError):
            return 0

    def read_report(self) -> dict[str, Any]:
        return json.loads(self.report_path.read_text())

    def stop(self) -> dict[str, Any]:
        """SIGINT, wait for exit 0, return the final report."""
        self.proc.send_signal(signal.SIGINT)
        try:
            code = self.proc.wait(timeout=STOP_TIMEOUT_S)
        finally:
            self.kill()
        assert code == 0, f"ros-station exited with {code}:\n{self.log()}"
        return self.read_report()

    def stop_json(self, sig: signal.Signals = signal.SIGTERM) -> dict[str, Any]:
        """Stop a station started without ``--report`` with ``sig``, wait for exit 0, and return its stdout read
        as one JSON document: the report, and nothing else."""
        self.proc.send_signal(sig)
        try:
            code = self.proc.wait(timeout=STOP_TIMEOUT_S)
        finally:
            self.kill()
        assert code == 0, f"ros-station exited with {code}:\n{self.log()}"
        return json.loads("".join(self.stdout))

    def kill(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGKILL)
            self.proc.wait(timeout=STOP_TIMEOUT_S)
        for t in self._threads:
            t.join(timeout=5.0)


@contextmanager
def roscore(env: dict[str, str]) -> Iterator[None]:
    """A roscore on the test's port, stopped on exit (even when the test fails)."""
    from ur3hanoi.interface.ros1.master import RosCore

    saved = {k: os.environ.get(k) for k in ("ROS_HOME", "ROS_IP")}
    os.environ.update(ROS_HOME=env["ROS_HOME"], ROS_IP=env["ROS_IP"])  # roscore inherits this process's env
    core = RosCore(env["ROS_MASTER_URI"])
    try:
        core.start()
        assert core.started, f"a master already answered at {env['ROS_MASTER_URI']}"
        yield
    finally:
        core.stop()
        for k, v in saved.items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v


@contextmanager
def station(env: dict[str, str], tmp_path: Path, *args: str, report: str | None = "report.json"
            ) -> Iterator[Station]:
    """``ur3hanoi ros-station --report tmp_path/report.json ARGS`` in its own session, ready; killed on exit.
    ``report=None``: without ``--report`` (the report on stdout: :meth:`Station.stop_json`)."""
    path = None if report is None else tmp_path / report
    where = [] if path is None else ["--report", str(path)]
    proc = subprocess.Popen(ur3hanoi_cmd("ros-station", *where, *args), env=env, text=True,
                            stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            start_new_session=True)
    st = Station(proc, path if path is not None else tmp_path / "no-report-file")
    try:
        st.wait_ready()
        yield st
    finally:
        st.kill()


def run(cmd: list[str], env: dict[str, str], timeout: float, stdin: str | None = None
        ) -> subprocess.CompletedProcess[str]:
    """Run a client to completion within ``timeout`` [s] (its whole process group is killed after that)."""
    proc = subprocess.Popen(cmd, env=env, text=True, stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    try:
        out, err = proc.communicate(stdin, timeout=timeout)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        raise AssertionError(f"{cmd} did not finish within {timeout} s:\n{out}\n{err}") from None
    finally:  # a station the script or client left in the background does not go on taking a core
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, signal.SIGKILL)
    return subprocess.CompletedProcess(cmd, proc.returncode, out, err)


def final_slots(report: dict[str, Any]) -> dict[int, tuple[int | None, int | None]]:
    """block -> (tower, height), 1-based, from a station report."""
    return {b["block"]: (b["tower"], b["height"]) for b in report["final"]["blocks"]}


def descendants(pid: int) -> set[int]:
    """Every process below ``pid`` (by parent id, read from /proc)."""
    parents: dict[int, int] = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            parents[int(entry.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    found: set[int] = set()
    todo = [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parents.items() if pp == p and c not in found]
        found.update(kids)
        todo += kids
    return found


def listening_addresses(pids: set[int]) -> list[tuple[str, int]]:
    """(address, port) of every listening TCP socket (IPv4 and IPv6) held by ``pids``, from /proc/net/tcp*."""
    inodes: set[str] = set()
    for pid in pids:
        try:
            for fd in Path(f"/proc/{pid}/fd").iterdir():
                try:
                    target = os.readlink(fd)
                except OSError:
                    continue
                if target.startswith("socket:["):
                    inodes.add(target[8:-1])
        except OSError:
            continue
    out = []
    for table, width in (("tcp", 8), ("tcp6", 32)):
        for line in Path(f"/proc/net/{table}").read_text().splitlines()[1:]:
            fields = line.split()
            if fields[3] != "0A" or fields[9] not in inodes:  # 0A: LISTEN
                continue
            hex_addr, hex_port = fields[1].split(":")
            raw = bytes.fromhex(hex_addr)
            if width == 8:
                addr = socket.inet_ntop(socket.AF_INET, raw[::-1])
            else:  # four little-endian 32-bit words
                addr = socket.inet_ntop(socket.AF_INET6, b"".join(raw[i:i + 4][::-1] for i in range(0, 16, 4)))
            out.append((addr, int(hex_port, 16)))
    return out
