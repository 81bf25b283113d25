"""set_io as the UR drivers answer it (the pin mapping, success = false for the rest), the io_states layout and the
one IOStates message a binding keeps."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pytest

from ur3hanoi.interface.urdriver.facts import (
    ANALOG_VOLTAGE,
    FUN_SET_ANALOG_OUT,
    FUN_SET_DIGITAL_OUT,
    FUN_SET_FLAG,
    FUN_SET_TOOL_VOLTAGE,
)
from ur3hanoi.interface.urdriver.io import IoBoard, IoStates, IoStatesMessage, check_set_io


@pytest.mark.parametrize("pin", [0, 7, 8, 15, 16, 17])
def test_digital_outputs_standard_configurable_and_tool(pin):
    assert check_set_io(FUN_SET_DIGITAL_OUT, pin, 1.0) is not None


@pytest.mark.parametrize(("fun", "pin", "state"), [
    (FUN_SET_DIGITAL_OUT, 18, 1.0), (FUN_SET_DIGITAL_OUT, -1, 0.0), (FUN_SET_FLAG, 0, 1.0),
    (FUN_SET_ANALOG_OUT, 2, 0.5), (FUN_SET_ANALOG_OUT, 0, 1.5), (FUN_SET_TOOL_VOLTAGE, 0, 5.0), (0, 0, 0.0),
    (FUN_SET_DIGITAL_OUT, 0, math.nan)])
def test_anything_else_answers_success_false(fun, pin, state):
    assert check_set_io(fun, pin, state) is None


def test_a_write_reaches_the_outputs_at_the_next_cycle():
    io = IoBoard()
    w = io.request(FUN_SET_DIGITAL_OUT, 1, 1.0)
    assert w is not None and not io.applied(w) and not io.digital_out(1)
    assert io.cycle() == [w]
    states = io.set_inputs({0: True}, {0: 1.9})
    assert io.applied(w) and io.digital_out(1) and states.digital_out[1]
    assert states.digital_in[0] and not any(states.digital_in[1:])
    assert states.analog_in == ((ANALOG_VOLTAGE, 1.9), (ANALOG_VOLTAGE, 0.0))
    assert len(states.digital_in) == len(states.digital_out) == 18 and len(states.analog_out) == 2
    t = io.request(FUN_SET_TOOL_VOLTAGE, 0, 24.0)
    assert t is not None
    io.cycle()
    assert io.applied(t) and io.tool_voltage == 24.0


class Msgs:
    """Message classes shaped like ``ur_msgs`` (keyword fields), as either binding passes them."""

    @dataclass
    class Digital:
        pin: int = 0
        state: bool = False

    @dataclass
    class Analog:
        pin: int = 0
        domain: int = 0
        state: float = 0.0

    @dataclass
    class IOStates:
        digital_in_states: list = field(default_factory=list)
        digital_out_states: list = field(default_factory=list)
        flag_states: list = field(default_factory=list)
        analog_in_states: list = field(default_factory=list)
        analog_out_states: list = field(default_factory=list)


def test_the_kept_message_holds_each_cycles_states() -> None:
    kept = IoStatesMessage(Msgs)
    first = IoStates(tuple(i == 0 for i in range(18)), tuple(i == 1 for i in range(18)), ((1, 1.9), (0, 0.004)),
                     ((1, 0.0), (1, 0.5)))
    msg = kept.update(first)
    assert [d.pin for d in msg.digital_in_states] == list(range(18)) and msg.flag_states == []
    assert [d.state for d in msg.digital_in_states] == list(first.digital_in)
    assert [d.state for d in msg.digital_out_states] == list(first.digital_out)
    assert [(a.pin, a.domain, a.state) for a in msg.analog_in_states] == [(0, 1, 1.9), (1, 0, 0.004)]
    later = IoStates(tuple(False for _ in range(18)), first.digital_out, ((1, 1.05), (0, 0.0)), first.analog_out)
    assert kept.update(later) is msg  # the same message, its values changed
    assert not any(d.state for d in msg.digital_in_states) and msg.digital_out_states[1].state
    assert [(a.domain, a.state) for a in msg.analog_in_states] == [(1, 1.05), (0, 0.0)]
