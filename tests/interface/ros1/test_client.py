"""RosArm's connection checks: it never publishes into the void and never waits forever."""

from __future__ import annotations

import sys

import pytest

from tests.support.ros_support import free_port, requires_ros, ros_env, roscore, run
from ur3hanoi.interface.errors import RosError
from ur3hanoi.interface.ros1.client import RosArm


def test_connect_without_a_master_fails_at_once():
    uri = f"http://127.0.0.1:{free_port()}"
    with pytest.raises(RosError, match=f"no ROS master answers at {uri}"):
        RosArm(master_uri=uri).connect()


@pytest.mark.ros
@requires_ros
def test_connect_to_a_master_without_a_driver_times_out_naming_the_topics(tmp_path):
    env = ros_env(free_port(), tmp_path)
    code = ("from ur3hanoi.interface.ros1.client import ArmConfig, RosArm\n"
            "RosArm(ArmConfig(connect_timeout_s=1.0)).connect()\n")
    with roscore(env):
        result = run([sys.executable, "-c", code], env, 60.0)
    assert result.returncode != 0
    assert ("RosError: no ur3/position, ur3/gripper_input, a ur3/command subscriber within 1 s on "
            f"{env['ROS_MASTER_URI']}: is ros-station or the course's ur3_driver running?") in result.stderr


class _Pub:
    def __init__(self) -> None:
        self.sent = 0

    def publish(self, msg: object) -> None:
        self.sent += 1


def test_a_driver_that_stops_publishing_is_named_within_the_position_timeout(monkeypatch):
    """No ur3/position for position_timeout_s while a move waits: one error naming the topic, long before the
    move timeout (not minutes of re-publishing and 'still 0.657 rad away')."""
    import numpy as np

    from ur3hanoi.interface.ros1.client import ArmConfig

    arm = RosArm(ArmConfig(position_timeout_s=0.2, move_timeout_s=30.0, republish_s=100.0), master_uri="http://x:1",
                 log=lambda s: None)
    arm._pub = _Pub()
    monkeypatch.setattr(arm, "_publish", lambda goal, io: object())
    arm._on_position(type("P", (), {"position": [0.0] * 6})())  # one message, then silence
    with pytest.raises(RosError, match=r"position updates stopped: no message on /ur3/position for 0\.\d s"):
        arm.move(np.full(6, 0.657))
