"""RosArm's connection checks: it never publishes into the void and never waits forever."""

from __future__ import annotations

import sys

import pytest

from tests.ros_support import free_port, requires_ros, ros_env, roscore, run
from ur3hanoi.ros.client import RosArm
from ur3hanoi.ros.errors import RosError


def test_connect_without_a_master_fails_at_once():
    uri = f"http://127.0.0.1:{free_port()}"
    with pytest.raises(RosError, match=f"no ROS master answers at {uri}"):
        RosArm(master_uri=uri).connect()


@pytest.mark.ros
@requires_ros
def test_connect_to_a_master_without_a_driver_times_out_naming_the_topics(tmp_path):
    env = ros_env(free_port(), tmp_path)
    code = ("from ur3hanoi.ros.client import ArmConfig, RosArm\n"
            "RosArm(ArmConfig(connect_timeout_s=1.0)).connect()\n")
    with roscore(env):
        result = run([sys.executable, "-c", code], env, 60.0)
    assert result.returncode != 0
    assert ("RosError: no ur3/position, ur3/gripper_input, a ur3/command subscriber within 1 s on "
            f"{env['ROS_MASTER_URI']}: is ros-station or the course's ur3_driver running?") in result.stderr
