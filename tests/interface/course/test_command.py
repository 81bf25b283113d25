"""Which ur3/command messages the station refuses, and that the messages say why."""

from __future__ import annotations

import math

import pytest

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.interface.common.errors import CommandError
from ur3hanoi.interface.course.command import parse_command
from ur3hanoi.robot.model import Q_HOME_LAB, JointLimits

LIM = JointLimits.ur3(elbow_limit=math.pi)


def test_valid_command_is_accepted_unchanged():
    cmd = parse_command(list(Q_HOME_LAB), 4.0, 4.0, True, LIM)
    assert cmd.destination == Q_HOME_LAB
    assert (cmd.v, cmd.a, cmd.io_0) == (4.0, 4.0, True)


@pytest.mark.parametrize(("destination", "v", "a", "needle"), [
    ([0.0] * 5, 1.0, 1.0, "destination has 5 values: expected 6"),
    ([0.0] * 7, 1.0, 1.0, "destination has 7 values: expected 6"),
    ([0.0, math.nan, 0, 0, 0, 0], 1.0, 1.0, "destination[1] = nan is invalid"),
    ([0.0, 0, 0, math.inf, 0, 0], 1.0, 1.0, "destination[3] = inf is invalid"),
    ([7.0, 0, 0, 0, 0, 0], 1.0, 1.0, "destination[0] = 7.0 rad is outside joint 1's limits"),
    ([0.0, 0, 3.2, 0, 0, 0], 1.0, 1.0, "outside joint 3's limits: expected -3.14159 <= q <= 3.14159"),
    ([0.0] * 6, 0.0, 1.0, "v = 0.0 is invalid: expected a finite number > 0"),
    ([0.0] * 6, 1.0, -2.0, "a = -2.0 is invalid"),
    ([0.0] * 6, math.nan, 1.0, "v = nan is invalid"),
])
def test_malformed_commands_are_refused_with_a_reason(destination, v, a, needle):
    with pytest.raises(CommandError) as err:
        parse_command(destination, v, a, False, LIM)
    assert needle in str(err.value)
    assert isinstance(err.value, Ur3HanoiError) and "\n" not in str(err.value)
