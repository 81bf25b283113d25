"""The ROS master: parse ``ROS_MASTER_URI``, ask whether a master answers, start and stop a ``roscore``.

:class:`RosCore` is a context manager: when no master answers at the URI (and the URI names this machine) it
starts ``roscore -p PORT`` in its own session, waits until its ``rosout`` node is registered too, and stops it on
exit (SIGINT, the way roscore wants to be stopped; SIGKILL of it and its children only if it does not exit within
the timeout). A master that already answers is
used and left running.
"""

from __future__ import annotations

import contextlib
import http.client
import os
import signal
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType
from typing import Any
from urllib.parse import urlsplit

from ur3hanoi.ros.env import roscore_executable
from ur3hanoi.ros.errors import RosError

DEFAULT_MASTER_URI = "http://localhost:11311"


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
        if self.host in ("localhost", "::1") or self.host.startswith("127."):
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


def master_pid(uri: str, timeout: float = 1.0) -> int | None:
    """The process id of the ROS master answering at ``uri``, or None when none answers within ``timeout`` [s]."""
    proxy = xmlrpc.client.ServerProxy(uri, transport=_TimeoutTransport(timeout))
    try:
        reply: Any = proxy.getPid("/ur3hanoi_probe")
        code, _msg, pid = reply
    except (OSError, xmlrpc.client.Error, ValueError, TypeError):
        return None
    return int(pid) if code == 1 else None


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


def _children(pid: int) -> list[int]:
    try:
        text = Path(f"/proc/{pid}/task/{pid}/children").read_text()
    except OSError:
        return []
    return [int(p) for p in text.split()]


class RosCore:
    """Use the master at ``uri``, starting ``roscore -p PORT`` when none answers (see the module docstring).

    Attributes:
        uri: the master URI.
        started: True when this object started the roscore (and will stop it).
    """

    def __init__(self, uri: str, start_timeout: float = 30.0, stop_timeout: float = 15.0) -> None:
        self.master = MasterUri.parse(uri)
        self.uri = uri
        self.start_timeout = start_timeout
        self.stop_timeout = stop_timeout
        self.started = False
        self._proc: subprocess.Popen[bytes] | None = None
        self._log: Path | None = None

    @property
    def pid(self) -> int | None:
        """Process id of the roscore this object started (None when it uses a running master)."""
        return None if self._proc is None else self._proc.pid

    def start(self) -> RosCore:
        """Start ``roscore`` unless a master answers. Raises RosError when it does not answer in time."""
        if master_answers(self.uri):
            return self
        if not self.master.is_local:
            raise RosError(f"no ROS master answers at {self.uri} and its host {self.master.host!r} is not this "
                           "machine: start roscore there, or set ROS_MASTER_URI to http://localhost:PORT")
        exe = roscore_executable()
        fd, log = tempfile.mkstemp(prefix=f"ur3hanoi-roscore-{self.master.port}-", suffix=".log")
        self._log = Path(log)
        env = dict(os.environ, ROS_MASTER_URI=self.uri)
        with os.fdopen(fd, "wb") as out:
            # Own session: a Ctrl-C in the terminal reaches the station first, which then stops roscore in order.
            self._proc = subprocess.Popen([exe, "-p", str(self.master.port)], stdin=subprocess.DEVNULL, stdout=out,
                                          stderr=subprocess.STDOUT, env=env, start_new_session=True)
        self.started = True
        deadline = time.monotonic() + self.start_timeout
        while time.monotonic() < deadline:
            # Up when rosout has registered too: roscore ignores a SIGINT that arrives while it still launches it.
            if node_registered(self.uri, "/rosout", timeout=0.5):
                return self
            if self._proc.poll() is not None:
                break
            time.sleep(0.1)
        tail = self._log_tail()
        self.stop()
        raise RosError(f"roscore -p {self.master.port} did not answer at {self.uri} within {self.start_timeout:g} s "
                       f"(port in use?): {tail}")

    def _log_tail(self) -> str:
        if self._log is None or not self._log.exists():
            return "no output"
        lines = [ln.strip() for ln in self._log.read_text(errors="replace").splitlines() if ln.strip()]
        return " | ".join(lines[-3:]) if lines else "no output"

    def stop(self) -> None:
        """Stop the roscore this object started (SIGINT, then SIGKILL of it and its children); no-op otherwise."""
        proc, self._proc = self._proc, None
        if proc is not None and proc.poll() is None:
            children = _children(proc.pid)
            try:
                # A second SIGINT covers one that roscore missed while it was busy launching its nodes.
                for wait_s in (min(5.0, self.stop_timeout), self.stop_timeout):
                    proc.send_signal(signal.SIGINT)
                    with contextlib.suppress(subprocess.TimeoutExpired):
                        proc.wait(timeout=wait_s)
                        break
                else:
                    raise subprocess.TimeoutExpired(proc.args, self.stop_timeout)
            except subprocess.TimeoutExpired:
                for pid in [*_children(proc.pid), *children]:
                    with contextlib.suppress(ProcessLookupError):
                        os.kill(pid, signal.SIGKILL)
                proc.kill()
                proc.wait(timeout=self.stop_timeout)
        if self._log is not None:
            self._log.unlink(missing_ok=True)
            self._log = None

    def __enter__(self) -> RosCore:
        return self.start()

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.stop()
