"""The ROS master: parse ``ROS_MASTER_URI``, ask whether a master answers, start and stop a ``roscore``.

:class:`RosCore` is a context manager: when no master answers at the URI (and the URI names this machine) it
starts ``roscore -p PORT`` under a guard process (:mod:`ur3hanoi.interface.ros1.guard`) and waits until its ``rosout``
node is registered too; on exit the guard stops it (SIGINT, the way roscore wants to be stopped; SIGKILL of what is
left). The guard also does so when the station dies, even by SIGKILL, and the roscore's logs live in a temporary folder
the guard removes. A master that already answers is used and left running, unless it is one a guard is stopping
because its station died (:func:`ur3hanoi.interface.ros1.guard.orphaned`): then :meth:`RosCore.start` waits until it is
gone and starts its own (a station restarted after a crash would otherwise attach to a master that vanishes a moment
later). Whether a master is still there while it is used is :mod:`ur3hanoi.interface.ros1.watch`'s.

Listening: the master started here binds and advertises ``host`` (``ROS_IP``; default ``127.0.0.1``, loopback
only; any other address binds all interfaces, as rosgraph does). On loopback it is ``rosmaster --core`` alone, the
master roscore would run, without roscore's ``rosout`` node: rosout's C++ XML-RPC server (xmlrpcpp) listens on
every interface whatever ``ROS_IP`` says (measured), and nothing the lab uses needs it (nodes log to their stderr
and log files; ``/rosout`` simply has no subscriber). With another ``host`` the full ``roscore`` runs.

A port where something accepts connections but does not answer like a master within :data:`PROBE_TIMEOUT_S` is
an error at once (no roscore is started there).
"""

from __future__ import annotations

import contextlib
import http.client
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
import time
import xmlrpc.client
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any
from urllib.parse import urlsplit

from ur3hanoi.interface.ros1.env import roscore_executable
from ur3hanoi.interface.ros1.errors import RosError

DEFAULT_MASTER_URI = "http://localhost:11311"

LOOPBACK = "127.0.0.1"
"""Default address the station and its roscore listen on and advertise (``ROS_IP``): this machine only."""

PROBE_TIMEOUT_S = 1.0
"""How long [s] a master may take to answer ``getPid`` before the URI counts as not answering."""
ORPHAN_WAIT_S = 5.0
"""How long [s] :meth:`RosCore.start` waits for a master whose station died to be stopped by its guard."""


def is_loopback(host: str) -> bool:
    """True for ``localhost``, 127.0.0.0/8 and ``::1``."""
    return host in ("localhost", "::1") or host.startswith("127.")


def listen_env(env: dict[str, str], host: str) -> dict[str, str]:
    """``env`` with ``ROS_IP=host``: Python nodes (rosgraph prefers ROS_IP) bind a loopback ``host`` only, any
    other address on all interfaces. For a loopback ``host`` also ``ROS_HOSTNAME=localhost``, which the C++ nodes
    (roscpp: rosout) read first and take as "loopback only"; otherwise no ``ROS_HOSTNAME``."""
    out = {k: v for k, v in env.items() if k != "ROS_HOSTNAME"}
    out["ROS_IP"] = host
    if is_loopback(host):
        out["ROS_HOSTNAME"] = "localhost"
    return out


@dataclass(frozen=True)
class MasterUri:
    """A parsed ``ROS_MASTER_URI`` (``http://HOST:PORT``)."""

    uri: str
    host: str
    port: int

    @classmethod
    def parse(cls, uri: str) -> MasterUri:
        """Parse ``uri``; raises RosError naming it unless it is ``http://HOST:PORT`` with 1 <= PORT <= 65535."""
        try:
            parts = urlsplit(uri)
            port = parts.port
        except ValueError:
            port = None
            parts = None
        if parts is None or parts.scheme != "http" or not parts.hostname or port is None or not 1 <= port <= 65535:
            raise RosError(f"ROS master URI {uri!r} is invalid: expected http://HOST:PORT, e.g. {DEFAULT_MASTER_URI}")
        return cls(uri=uri, host=parts.hostname, port=port)

    @property
    def is_local(self) -> bool:
        """True when the host is this machine (loopback, or its own host name)."""
        if is_loopback(self.host):
            return True
        return self.host in (socket.gethostname(), socket.getfqdn())


def master_uri_from_env() -> str:
    """``ROS_MASTER_URI`` from the environment, or :data:`DEFAULT_MASTER_URI`."""
    return os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI


class _TimeoutTransport(xmlrpc.client.Transport):
    """xmlrpc transport whose connections give up after ``timeout`` [s] (the stdlib's wait forever)."""

    def __init__(self, timeout: float) -> None:
        super().__init__()
        self._timeout = timeout

    def make_connection(self, host: tuple[str, dict[str, str]] | str) -> http.client.HTTPConnection:
        conn = super().make_connection(host)
        conn.timeout = self._timeout
        return conn


def probe_master(uri: str, timeout: float = PROBE_TIMEOUT_S) -> int | None:
    """The process id of the ROS master answering at ``uri``; None when nothing listens there.

    Raises:
        RosError: something accepts connections at ``uri`` but does not answer like a ROS master within
            ``timeout`` [s] (each of connect and reply).
    """
    proxy = xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout))
    try:
        reply: Any = proxy.getPid("/ur3hanoi_probe")
        code, _msg, pid = reply
        if code == 1:
            return int(pid)
        why = f"it answered {reply!r}"
    except ConnectionRefusedError:
        return None
    except TimeoutError:
        why = f"no answer within {timeout:g} s"
    except (OSError, xmlrpc.client.Error, ValueError, TypeError) as exc:
        why = f"{type(exc).__name__}: {exc}"
    raise RosError(f"something at {uri} accepts connections but is not a ROS master ({why}): stop it, or use "
                   "another port (--master http://localhost:PORT)")


def master_pid(uri: str, timeout: float = PROBE_TIMEOUT_S) -> int | None:
    """The process id of the ROS master answering at ``uri``, or None when none answers within ``timeout`` [s]."""
    try:
        return probe_master(uri, timeout)
    except RosError:
        return None


def node_registered(uri: str, node: str, timeout: float = 1.0) -> bool:
    """True when the master at ``uri`` knows ``node`` (e.g. ``/rosout``), within ``timeout`` [s]."""
    proxy = xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout))
    try:
        reply: Any = proxy.lookupNode("/ur3hanoi_probe", node)
        return bool(reply[0] == 1)
    except (OSError, xmlrpc.client.Error, ValueError, TypeError, IndexError):
        return False


def master_answers(uri: str, timeout: float = 1.0) -> bool:
    """True when a ROS master answers at ``uri`` within ``timeout`` [s]."""
    return master_pid(uri, timeout) is not None


class RosCore:
    """Use the master at ``uri``, starting ``roscore -p PORT`` when none answers (see the module docstring).

    Args:
        uri: the master URI.
        host: address the roscore started here listens on and advertises (default loopback only).

    Attributes:
        started: True when this object started the roscore (and will stop it).
    """

    def __init__(self, uri: str, start_timeout: float = 30.0, stop_timeout: float = 5.0,
                 host: str = LOOPBACK) -> None:
        self.master = MasterUri.parse(uri)
        self.uri = uri
        self.host = host
        self.start_timeout = start_timeout
        self.stop_timeout = stop_timeout
        self.started = False
        self._guard: subprocess.Popen[bytes] | None = None
        self._pid: int | None = None
        self._exit: int | None = None
        self._log_dir: Path | None = None
        self._buf = b""

    @property
    def pid(self) -> int | None:
        """Process id of the roscore this object started (None when it uses a running master)."""
        return self._pid

    @property
    def guard_pid(self) -> int | None:
        """Process id of the guard (:mod:`ur3hanoi.interface.ros1.guard`) of the roscore this object started, or
        None."""
        return None if self._guard is None else self._guard.pid

    @property
    def log_dir(self) -> Path | None:
        """The temporary folder of the roscore's logs (removed when it stops), or None."""
        return self._log_dir

    @property
    def with_rosout(self) -> bool:
        """True when the full ``roscore`` (with ``rosout``) is started: ``host`` is not loopback."""
        return not is_loopback(self.host)

    def start(self) -> RosCore:
        """Start ``roscore`` (``rosmaster`` on loopback) unless a master answers (one being stopped because its
        station died is waited out first). Raises RosError when it does not answer in time, or something else
        holds the port."""
        from ur3hanoi.interface.ros1 import guard

        if self._running_master() is not None:
            return self
        if not self.master.is_local:
            raise RosError(f"no ROS master answers at {self.uri} and its host {self.master.host!r} is not this "
                           "machine: start roscore there, or set ROS_MASTER_URI to http://localhost:PORT")
        exe = roscore_executable("roscore" if self.with_rosout else "rosmaster")
        args = [exe, "-p", str(self.master.port)] if self.with_rosout else [exe, "--core", "-p", str(self.master.port)]
        guard.remove_stale_log_dirs()
        self._log_dir = guard.make_log_dir()
        self._exit, self._buf = None, b""
        env = listen_env(dict(os.environ, ROS_MASTER_URI=self.uri), self.host)
        # The guard (own session: a Ctrl-C in the terminal reaches the station first, which then stops roscore in
        # order) reads the pipe on its stdin: end of file, when this process closes it or dies, stops roscore.
        self._guard = subprocess.Popen(
            [sys.executable, "-m", guard.__name__, str(self._log_dir), "--", *args],
            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, env=env,
            start_new_session=True, bufsize=0)
        self.started = True
        deadline = time.monotonic() + self.start_timeout
        while time.monotonic() < deadline:
            self._read_guard()
            # Up when rosout has registered too: roscore ignores a SIGINT that arrives while it still launches it.
            if self._pid is not None and (node_registered(self.uri, "/rosout", timeout=0.5) if self.with_rosout
                                          else master_answers(self.uri, timeout=0.5)):
                return self
            if self._exit is not None or self._guard.poll() is not None:
                break
            time.sleep(0.1)
        tail = self._log_tail()
        self.stop()
        raise RosError(f"roscore -p {self.master.port} did not answer at {self.uri} within {self.start_timeout:g} s "
                       f"(port in use?): {tail}")

    def _running_master(self) -> int | None:
        """The pid of the master answering at the URI, after waiting out one its guard is stopping (None: none)."""
        from ur3hanoi.interface.ros1.guard import orphaned

        pid = probe_master(self.uri)
        deadline = time.monotonic() + ORPHAN_WAIT_S
        while pid is not None and orphaned(pid):
            if time.monotonic() > deadline:
                raise RosError(f"the ROS master at {self.uri} (pid {pid}) belongs to a station that died and is "
                               f"still being stopped after {ORPHAN_WAIT_S:g} s: try again in a moment")
            time.sleep(0.05)
            pid = probe_master(self.uri)
        return pid

    def _read_guard(self) -> None:
        """Take the guard's ``pid N`` / ``exit CODE`` lines that are there (never blocks)."""
        guard = self._guard
        if guard is None or guard.stdout is None:
            return
        fd = guard.stdout.fileno()
        while select.select([fd], [], [], 0)[0]:
            chunk = os.read(fd, 4096)
            if not chunk:
                break
            self._buf += chunk
        *lines, self._buf = self._buf.split(b"\n")
        for raw in lines:
            words = raw.decode(errors="replace").split()
            if len(words) == 2 and words[0] == "pid":
                self._pid = int(words[1])
            elif len(words) == 2 and words[0] == "exit":
                self._exit = int(words[1])

    def _log_tail(self) -> str:
        log = None if self._log_dir is None else self._log_dir / "roscore.log"
        if log is None or not log.exists():
            return "no output"
        lines = [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.strip()]
        return " | ".join(lines[-3:]) if lines else "no output"

    def stop(self) -> None:
        """Stop the roscore this object started (close the guard's pipe and wait); no-op otherwise."""
        guard, self._guard = self._guard, None
        if guard is not None:
            with contextlib.suppress(OSError):
                if guard.stdin is not None:
                    guard.stdin.close()
            try:
                guard.wait(timeout=self.stop_timeout + 10.0)
            except subprocess.TimeoutExpired:
                if self._pid is not None:
                    for pid in [*_children(self._pid), self._pid]:
                        with contextlib.suppress(ProcessLookupError):
                            os.kill(pid, signal.SIGKILL)
                guard.kill()
                guard.wait(timeout=self.stop_timeout)
            if guard.stdout is not None:
                guard.stdout.close()
        self._pid = None
        if self._log_dir is not None:
            shutil.rmtree(self._log_dir, ignore_errors=True)
            self._log_dir = None

    def __enter__(self) -> RosCore:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.stop()


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]
