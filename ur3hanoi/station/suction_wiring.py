"""Where the suction is wired on the robot's IO, for the official UR drivers (``set_io``, ``io_states``).

A calibration's optional ``io:`` section names the pins (see ``ur3hanoi/station/shipped/README.md``)::

    io:
      suction_output: 1        # the digital output switching the cup: set_io pin 0-7 standard, 8-15
                               # configurable, 16-17 tool
      vacuum_generator_output: 12  # the output switching the vacuum generator, on for the whole solve (same
                               # pins), or null: the cell has none (the cup's output is all there is)
      vacuum_switch_input: 0   # the vacuum switch: io_states digital input 0-17 (a block is held when it reads 1)
      vacuum_sensor_input: 0   # the vacuum sensor: io_states standard analog input 0-1 [V]

Each key defaults to the course's wiring on the calibration's arm (:attr:`ur3hanoi.robot.registry.RobotDescription.
course_suction_io`, :attr:`~ur3hanoi.robot.registry.RobotDescription.course_vacuum_generator`): on a UR3 (ECE 470)
the course driver's ``set_digital_out(0, ...)`` for ``io_0``, no generator output, Digital Input 0 / Analog Input 0;
on a UR3e (UMD ENME480) the bridge's generator on pin 12 (configurable output 4: on at start, off on exit), the cup
on digital output 1, digital input 0, analog input 0. A file without ``vacuum_generator_output`` (written before it
existed) gets its arm's default. The course's own topics (``ur3/command``'s ``io_0``, ``gripper_input``) do not use
this section: their drivers map the pins themselves.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ur3hanoi.errors import CalibrationError
from ur3hanoi.io.schema import Field, Nullable, Number, Record
from ur3hanoi.robot.registry import RobotDescription

DIGITAL_PINS = 18
"""``set_io`` digital output pins and ``io_states`` digital inputs: 0..17."""
ANALOG_INPUTS = 2
"""Standard analog inputs in ``io_states``: 0..1."""
GENERATOR_KEY = "vacuum_generator_output"
"""The ``io`` key of the vacuum generator's output (the file's name for :attr:`SuctionWiring.generator`)."""


def output_name(pin: int) -> str:
    """The controller's name of ``set_io`` output ``pin`` (0-17): ``digital output 1``, ``configurable output 4
    (set_io pin 12)``, ``tool output 0 (set_io pin 16)``."""
    if pin < 8:
        return f"digital output {pin}"
    if pin < 16:
        return f"configurable output {pin - 8} (set_io pin {pin})"
    return f"tool output {pin - 16} (set_io pin {pin})"


@dataclass(frozen=True)
class SuctionWiring:
    """The suction's pins: the output switching the cup, the vacuum switch's digital input, the sensor's analog
    input, and the output switching the vacuum generator (None: the cell has none)."""

    output: int
    switch_input: int
    sensor_input: int
    generator: int | None = None

    @property
    def outputs(self) -> tuple[int, ...]:
        """Every output the suction needs on (the generator's first, as a session switches them on), to switch
        off at the end."""
        return (self.output,) if self.generator is None else (self.generator, self.output)

    def describe(self) -> str:
        """``suction on DO 1, vacuum generator on DO 12`` (``set_io`` pins), for a station's ready line."""
        return f"suction on DO {self.output}" + ("" if self.generator is None else
                                                 f", vacuum generator on DO {self.generator}")

    def as_dict(self) -> dict[str, int | None]:
        """The ``io:`` section of a calibration file."""
        return {"suction_output": self.output, GENERATOR_KEY: self.generator,
                "vacuum_switch_input": self.switch_input, "vacuum_sensor_input": self.sensor_input}


def course_wiring(robot: RobotDescription) -> SuctionWiring:
    """The course's wiring on ``robot`` (see the module docstring)."""
    return SuctionWiring(*robot.course_suction_io, generator=robot.course_vacuum_generator)


_PIN = Number(0, DIGITAL_PINS - 1, integer=True)
IO_SECTION = Record({
    "suction_output": Field(_PIN, required=False),
    GENERATOR_KEY: Field(Nullable(_PIN), required=False),
    "vacuum_switch_input": Field(_PIN, required=False),
    "vacuum_sensor_input": Field(Number(0, ANALOG_INPUTS - 1, integer=True), required=False),
})
"""The schema of a calibration file's ``io:`` section (a part of ``STATION_SCHEMA``)."""


def parse_wiring(section: Mapping[str, Any] | None, robot: RobotDescription, source: str = "") -> SuctionWiring:
    """The wiring of a (schema-checked) ``io`` section of file ``source``; absent keys from the course's wiring on
    ``robot``.

    Raises:
        CalibrationError: the generator's output is the cup's (one output cannot switch both).
    """
    default = course_wiring(robot)
    if section is None:
        return default
    generator = section.get(GENERATOR_KEY, default.generator)  # present as null: no generator
    wiring = SuctionWiring(int(section.get("suction_output", default.output)),
                           int(section.get("vacuum_switch_input", default.switch_input)),
                           int(section.get("vacuum_sensor_input", default.sensor_input)),
                           None if generator is None else int(generator))
    if wiring.generator == wiring.output:
        raise CalibrationError.invalid(
            source, f"io.{GENERATOR_KEY}", wiring.generator,
            f"an integer in [0, {DIGITAL_PINS - 1}] other than io.suction_output ({wiring.output}: the cup's own "
            "output), or null for a cell without a vacuum generator output")
    return wiring


__all__ = ["GENERATOR_KEY", "IO_SECTION", "SuctionWiring", "course_wiring", "output_name", "parse_wiring"]
