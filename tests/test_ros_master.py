"""ROS_MASTER_URI parsing and the roscore lifecycle (start when none answers, leave a running one alone)."""

from __future__ import annotations

import os
import time

import pytest

from tests.ros_support import free_port, requires_ros, ros_env
from ur3hanoi.ros.errors import RosError
from ur3hanoi.ros.master import MasterUri, RosCore, master_answers, master_pid


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
            assert master_answers(uri)
            pid = master_pid(uri)
            with RosCore(uri) as guest:  # a master answers: used, not started, not stopped
                assert not guest.started
            assert master_pid(uri) == pid
        assert not master_answers(uri)
        assert owner.pid is None
        with pytest.raises(ProcessLookupError):
            os.kill(pid, 0)  # rosmaster is gone too
    finally:
        owner.stop()
