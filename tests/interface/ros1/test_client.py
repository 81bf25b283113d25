"""RosArm's connection checks: it never publishes into the void and never waits forever."""

from __future__ import annotations

import sys

import pytest

from tests.support.ros_support import free_port, requires_ros, ros_env, roscore, run
from ur3hanoi.errors import DriverError
from ur3hanoi.interface.ros1.client import RosArm
from ur3hanoi.interface.ros1.errors import RosError


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
    assert ("DriverError: no ur3/position, ur3/gripper_input, a ur3/command subscriber within 1 s on "
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
    monkeypatch.setattr(arm, "_publish", lambda goal, io, v, a: object())
    arm._on_position(type("P", (), {"position": [0.0] * 6})())  # one message, then silence
    with pytest.raises(DriverError, match=r"position updates stopped: no message on /ur3/position for 0\.\d s"):
        arm.move(np.full(6, 0.657))


def test_positions_are_kept_with_their_arrival_times_and_a_malformed_one_is_named_not_taken():
    """What `teach` asks of the arm: the positions of the last seconds (is the arm still?), and a driver that
    publishes 5 joints or NaN named instead of taken."""
    import math
    import time

    import numpy as np

    from ur3hanoi.interface.course.client import HISTORY_S

    arm = RosArm(master_uri="http://x:1", log=lambda s: None)
    t0 = time.monotonic()
    for i in range(5):
        arm._on_position(type("P", (), {"position": [0.1 * i] * 6})())
    window = arm.samples(10.0)
    assert [round(float(q[0]), 9) for _, q in window] == [0.0, 0.1, 0.2, 0.3, 0.4]
    times = [t for t, _ in window]
    assert t0 <= times[0] and times == sorted(times) and times[-1] <= time.monotonic()
    assert arm.malformed == ""
    arm._on_position(type("P", (), {"position": [0.1] * 5})())
    assert arm.malformed == "5 joint values (expected 6)" and float(arm.q[0]) == 0.4
    arm._on_position(type("P", (), {"position": [0.1, math.nan, 0.1, 0.1, 0.1, 0.1]})())
    assert arm.malformed.startswith("a non-finite joint value (0.1, nan,")
    assert len(arm.samples(10.0)) == 5 and HISTORY_S >= 0.5  # stillness needs at least half a second
    sent: list[tuple[object, ...]] = []
    arm._publish = lambda goal, io, v, a: sent.append((tuple(np.round(goal, 3)), io, v, a))  # type: ignore[method-assign]
    arm.send(np.full(6, 0.5), 0.35, 0.7)
    assert sent == [((0.5,) * 6, False, 0.35, 0.7)] and arm.commands_sent == 1
