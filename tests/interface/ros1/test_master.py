"""ROS_MASTER_URI parsing and the roscore lifecycle (start when none answers, leave a running one alone)."""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest

from tests.support.reaper import alive
from tests.support.ros_support import free_port, requires_ros, ros_env
from ur3hanoi.interface.ros1.errors import RosError
from ur3hanoi.interface.ros1.guard import LOG_DIR_PREFIX, remove_stale_log_dirs
from ur3hanoi.interface.ros1.master import MasterUri, RosCore, listen_env, master_answers, master_pid, probe_master


def test_parse_master_uri():
    m = MasterUri.parse("http://127.0.0.1:11411")
    assert (m.host, m.port, m.is_local) == ("127.0.0.1", 11411, True)
    assert MasterUri.parse("http://localhost:11311/").is_local
    assert not MasterUri.parse("http://robot-pc.example:11311").is_local
    for bad in ("localhost:11311", "http://localhost", "https://localhost:11311", "http://localhost:99999", ""):
        with pytest.raises(RosError, match="is invalid: expected http://HOST:PORT"):
            MasterUri.parse(bad)


def test_no_master_answers_on_a_free_port_quickly():
    t0 = time.monotonic()
    assert not master_answers(f"http://127.0.0.1:{free_port()}", timeout=1.0)
    assert time.monotonic() - t0 < 2.0


@pytest.mark.ros
@requires_ros
def test_roscore_started_once_used_twice_stopped_by_its_owner(tmp_path, monkeypatch):
    env = ros_env(free_port(), tmp_path)
    monkeypatch.setenv("ROS_HOME", env["ROS_HOME"])
    uri = env["ROS_MASTER_URI"]
    owner = RosCore(uri)
    try:
        with owner:
            assert owner.started and owner.pid is not None
            log_dir = owner.log_dir
            assert log_dir is not None and log_dir.is_dir()
            assert master_answers(uri)
            pid = master_pid(uri)
            with RosCore(uri) as guest:  # a master answers: used, not started, not stopped
                assert not guest.started
            assert master_pid(uri) == pid
        assert not master_answers(uri)
        assert owner.pid is None and not log_dir.exists()
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)  # rosmaster is gone too
    finally:
        owner.stop()


def test_a_port_that_accepts_and_never_answers_is_an_error_within_the_probe_timeout():
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen(4)  # the backlog accepts; nothing ever answers
        uri = f"http://127.0.0.1:{server.getsockname()[1]}"
        assert master_pid(uri, timeout=0.3) is None
        with pytest.raises(RosError, match=r"accepts connections but is not a ROS master \(no answer within 0\.3 s\)"):
            probe_master(uri, timeout=0.3)
        with pytest.raises(RosError, match="accepts connections but is not a ROS master"):
            RosCore(uri).start()  # no roscore is started on a port something else holds
    assert probe_master(f"http://127.0.0.1:{free_port()}") is None  # nothing listens: start one


def test_listen_env_is_loopback_unless_a_lab_address_is_given():
    env = {"ROS_HOSTNAME": "lab-pc", "ROS_IP": "10.0.0.5", "HOME": "/h"}
    assert listen_env(env, "127.0.0.1") == {"ROS_IP": "127.0.0.1", "ROS_HOSTNAME": "localhost", "HOME": "/h"}
    assert listen_env(env, "192.168.1.20") == {"ROS_IP": "192.168.1.20", "HOME": "/h"}
    assert not RosCore("http://127.0.0.1:11311").with_rosout
    assert RosCore("http://127.0.0.1:11311", host="192.168.1.20").with_rosout


def test_stale_log_dirs_of_dead_stations_are_removed(tmp_path):
    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = tmp_path / f"{LOG_DIR_PREFIX}{dead.pid}-abc"
    live = tmp_path / f"{LOG_DIR_PREFIX}{os.getpid()}-def"
    other = tmp_path / "ur3hanoi-roscore-notapid"
    for d in (stale, live, other):
        d.mkdir()
        (d / "master.log").write_text("x")
    assert remove_stale_log_dirs(tmp_path) == [stale]
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, other.name])


@pytest.mark.ros
@requires_ros
def test_the_guard_stops_the_master_and_removes_its_logs_on_sigterm_too(tmp_path, monkeypatch):
    env = ros_env(free_port(), tmp_path)
    monkeypatch.setenv("ROS_HOME", env["ROS_HOME"])
    uri = env["ROS_MASTER_URI"]
    core = RosCore(uri)
    try:
        core.start()
        log_dir, guard = core.log_dir, core.guard_pid
        assert log_dir is not None and guard is not None and (log_dir / "roscore.log").exists()
        pid = master_pid(uri)
        os.kill(guard, signal.SIGTERM)  # e.g. a system shutdown
        deadline = time.monotonic() + 30.0
        while alive(guard) and time.monotonic() < deadline:
            time.sleep(0.1)
        assert not alive(guard) and not master_answers(uri) and not log_dir.exists()
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)
    finally:
        core.stop()


@pytest.mark.ros
@requires_ros
def test_the_master_the_guard_starts_obeys_sigint_and_the_guard_stops_on_sigint(tmp_path, monkeypatch):
    """The guard's rosmaster starts with SIGINT at its default (it inherited the guard's ignored SIGINT across exec,
    and every stop waited 15 s for a SIGKILL): a SIGINT stops it at once. A SIGINT to the guard stops it cleanly."""
    env = ros_env(free_port(), tmp_path)
    monkeypatch.setenv("ROS_HOME", env["ROS_HOME"])
    uri = env["ROS_MASTER_URI"]
    core = RosCore(uri)
    try:
        core.start()
        pid, guard = master_pid(uri), core.guard_pid
        assert pid is not None and guard is not None
        os.kill(pid, signal.SIGINT)
        deadline = time.monotonic() + 2.0
        while alive(pid) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not alive(pid) and not master_answers(uri), "rosmaster ignored SIGINT"
        assert alive(guard)  # it reports the exit and waits for its station
        os.kill(guard, signal.SIGINT)
        deadline = time.monotonic() + 2.0
        while alive(guard) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert not alive(guard) and core.log_dir is not None and not core.log_dir.exists()
    finally:
        core.stop()


@pytest.mark.ros
@requires_ros
def test_a_master_whose_station_died_is_waited_out_not_attached_to(tmp_path, monkeypatch):
    """A station's master outlives it for a moment (its guard is stopping it; here the guard is held with SIGSTOP
    for 1 s): a RosCore started on the same URI meanwhile waits until it is gone and starts its own, instead of
    attaching to a master that vanishes a moment later."""
    env = ros_env(free_port(), tmp_path)
    monkeypatch.setenv("ROS_HOME", env["ROS_HOME"])
    uri = env["ROS_MASTER_URI"]
    code = ("import sys, time\nfrom ur3hanoi.interface.ros1.master import RosCore\n"
            f"c = RosCore({uri!r}).start()\nprint(c.guard_pid, flush=True)\ntime.sleep(60)\n")
    crashed = subprocess.Popen([sys.executable, "-c", code], env=env, text=True, stdout=subprocess.PIPE,
                               start_new_session=True)
    core, guard = RosCore(uri), 0
    try:
        assert crashed.stdout is not None
        guard = int(crashed.stdout.readline())
        old = master_pid(uri)
        assert old is not None
        os.kill(guard, signal.SIGSTOP)
        os.kill(crashed.pid, signal.SIGKILL)
        crashed.wait()
        threading.Timer(1.0, os.kill, (guard, signal.SIGCONT)).start()
        t0 = time.monotonic()
        core.start()
        assert core.started and time.monotonic() - t0 >= 1.0
        assert master_pid(uri) not in (None, old) and not alive(old)
        # the guard ends just after its master (its last clean-up can outlast the new start on a loaded machine)
        deadline = time.monotonic() + 5.0
        while alive(guard) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not alive(guard)
    finally:
        if guard:
            with contextlib.suppress(ProcessLookupError):
                os.kill(guard, signal.SIGCONT)
        core.stop()
        if crashed.poll() is None:
            crashed.kill()
