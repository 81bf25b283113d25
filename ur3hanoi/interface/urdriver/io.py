"""The UR controller's IO as the drivers serve it: ``set_io`` requests and the ``io_states`` snapshot.

:func:`check_set_io` is the drivers' ``setIO`` (URD1 ``hardware_interface.cpp``; URCL's ``RTDEWriter``): function
``FUN_SET_DIGITAL_OUT`` on pins 0-7 (standard outputs), 8-15 (configurable, pin - 8) and 16-17 (tool, pin - 16);
``FUN_SET_ANALOG_OUT`` on outputs 0-1 with a value in [0, 1]; ``FUN_SET_TOOL_VOLTAGE`` with 0, 12 or 24 V; anything
else (``FUN_SET_FLAG`` included, or a pin out of range) answers ``success = false`` and changes nothing.

:class:`IoBoard` holds the states: a write accepted now reaches the outputs at the next control cycle
(:meth:`IoBoard.cycle`: the RTDE write goes out with the next package), which is when ``io_states`` shows it. The ROS 1
driver answers once the write is queued, the ROS 2 one once the output changed
(:attr:`~ur3hanoi.interface.urdriver.profile.ControllerProfile.set_io_waits`: its binding waits with
:meth:`IoBoard.applied`).

:class:`IoStates` is one ``ur_msgs/IOStates`` message: 18 digital inputs and outputs (``pin`` = index), the 2 standard
analog inputs and outputs with their domain (current or voltage), no flags. The station writes the inputs
(:meth:`IoBoard.set_inputs`: the suction feedback on the calibration's pins).
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass
from typing import Any

from ur3hanoi.interface.urdriver.facts import (
    ANALOG_VOLTAGE,
    CONFIGURABLE_DO,
    FUN_SET_ANALOG_OUT,
    FUN_SET_DIGITAL_OUT,
    FUN_SET_TOOL_VOLTAGE,
    N_ANALOG,
    N_DIGITAL,
    STANDARD_DO,
    TOOL_DO,
    TOOL_VOLTAGES,
)


@dataclass(frozen=True)
class SetIo:
    """An accepted ``set_io`` write: ``fun``, ``pin``, ``state`` as requested."""

    fun: int
    pin: int
    state: float


@dataclass(frozen=True)
class IoStates:
    """One ``ur_msgs/IOStates``: digital states by pin (18 each); analog ``(domain, value)`` by pin (2 each)."""

    digital_in: tuple[bool, ...]
    digital_out: tuple[bool, ...]
    analog_in: tuple[tuple[int, float], ...]
    analog_out: tuple[tuple[int, float], ...]


def check_set_io(fun: int, pin: int, state: float) -> SetIo | None:
    """The write ``set_io(fun, pin, state)`` makes, or None when the driver answers ``success = false``."""
    if not math.isfinite(state):
        return None
    if fun == FUN_SET_DIGITAL_OUT and (pin in STANDARD_DO or pin in CONFIGURABLE_DO or pin in TOOL_DO):
        return SetIo(fun, pin, state)
    if fun == FUN_SET_ANALOG_OUT and 0 <= pin < N_ANALOG and 0.0 <= state <= 1.0:
        return SetIo(fun, pin, state)
    if fun == FUN_SET_TOOL_VOLTAGE and state in TOOL_VOLTAGES:
        return SetIo(fun, pin, state)
    return None


class IoBoard:
    """The controller's inputs and outputs (see the module docstring). Thread-safe: bindings call
    :meth:`request` and :meth:`applied` from their threads, the control loop :meth:`cycle`."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._pending: list[SetIo] = []
        self._digital_out = [False] * N_DIGITAL
        self._analog_out = [0.0] * N_ANALOG
        self.tool_voltage = 0.0
        self._states = IoStates((False,) * N_DIGITAL, (False,) * N_DIGITAL, ((ANALOG_VOLTAGE, 0.0),) * N_ANALOG,
                                ((ANALOG_VOLTAGE, 0.0),) * N_ANALOG)
        self.writes = 0  # accepted writes applied

    def request(self, fun: int, pin: int, state: float) -> SetIo | None:
        """Queue ``set_io(fun, pin, state)`` for the next cycle; None (``success = false``) when the driver
        refuses it."""
        write = check_set_io(fun, pin, state)
        if write is not None:
            with self._lock:
                self._pending.append(write)
        return write

    def applied(self, write: SetIo) -> bool:
        """True once ``write`` is out (its output reads its state)."""
        with self._lock:
            if write in self._pending:
                return False
        if write.fun == FUN_SET_DIGITAL_OUT:
            return self._states.digital_out[write.pin] == (write.state != 0.0)
        if write.fun == FUN_SET_ANALOG_OUT:
            return self._states.analog_out[write.pin][1] == write.state
        return self.tool_voltage == write.state

    def cycle(self) -> list[SetIo]:
        """Apply the writes queued since the last cycle (in order); returns them."""
        with self._lock:
            pending, self._pending = self._pending, []
        for w in pending:
            if w.fun == FUN_SET_DIGITAL_OUT:
                self._digital_out[w.pin] = w.state != 0.0
            elif w.fun == FUN_SET_ANALOG_OUT:
                self._analog_out[w.pin] = w.state
            else:
                self.tool_voltage = w.state
        self.writes += len(pending)
        return pending

    def digital_out(self, pin: int) -> bool:
        """The output ``pin`` (0-17) as applied."""
        return self._digital_out[pin]

    def set_inputs(self, digital: dict[int, bool], analog: dict[int, float]) -> IoStates:
        """Set these input pins (others read False / 0 V) and return the new ``io_states`` (once per control
        cycle: the few given pins are written into the defaults, not every pin looked up)."""
        d_in = [False] * N_DIGITAL
        for pin, on in digital.items():
            if 0 <= pin < N_DIGITAL:
                d_in[pin] = on
        a_in = [(ANALOG_VOLTAGE, 0.0)] * N_ANALOG
        for pin, volts in analog.items():
            if 0 <= pin < N_ANALOG:
                a_in[pin] = (ANALOG_VOLTAGE, float(volts))
        self._states = IoStates(tuple(d_in), tuple(self._digital_out), tuple(a_in),
                                tuple((ANALOG_VOLTAGE, v) for v in self._analog_out))
        return self._states

    @property
    def states(self) -> IoStates:
        """The last ``io_states`` (an immutable snapshot)."""
        return self._states


class IoStatesMessage:
    """One ``ur_msgs/IOStates`` message kept across cycles, for either binding (``msgs``: anything with the message
    classes ``IOStates``, ``Digital`` and ``Analog``: ROS 2's ``ur_msgs.msg`` module, ROS 1's generated classes): 18
    digital in and out, 2 analog in and out, no flags, ``pin`` = index, as the driver publishes. :meth:`update`
    writes only the values that changed: building 40 nested messages every cycle costs a 500 Hz loop a tenth of its
    period. Both middlewares serialize a message when it is published, so the next cycle may change it."""

    def __init__(self, msgs: Any) -> None:
        self.msg = msgs.IOStates(
            digital_in_states=[msgs.Digital(pin=i, state=False) for i in range(N_DIGITAL)],
            digital_out_states=[msgs.Digital(pin=i, state=False) for i in range(N_DIGITAL)], flag_states=[],
            analog_in_states=[msgs.Analog(pin=i, domain=ANALOG_VOLTAGE, state=0.0) for i in range(N_ANALOG)],
            analog_out_states=[msgs.Analog(pin=i, domain=ANALOG_VOLTAGE, state=0.0) for i in range(N_ANALOG)])
        self._last: IoStates | None = None

    def update(self, io: IoStates) -> Any:
        """The message holding ``io``."""
        last, m = self._last, self.msg
        for field, items, values in (("digital_in", m.digital_in_states, io.digital_in),
                                     ("digital_out", m.digital_out_states, io.digital_out)):
            if last is None or getattr(last, field) != values:
                for item, on in zip(items, values, strict=True):
                    item.state = bool(on)
        for items, analog in ((m.analog_in_states, io.analog_in), (m.analog_out_states, io.analog_out)):
            for item, (domain, value) in zip(items, analog, strict=True):
                item.domain, item.state = domain, float(value)
        self._last = io
        return m
