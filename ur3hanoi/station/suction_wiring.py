"""Where the suction is wired on the robot's IO, for the official UR drivers (``set_io``, ``io_states``).

A calibration's optional ``io:`` section names the pins (see ``ur3hanoi/station/shipped/README.md``)::

    io:
      suction_output: 1        # the digital output switching the vacuum: set_io pin 0-7 standard, 8-15
                               # configurable, 16-17 tool
      vacuum_switch_input: 0   # the vacuum switch: io_states digital input 0-17 (a block is held when it reads 1)
      vacuum_sensor_input: 0   # the vacuum sensor: io_states standard analog input 0-1 [V]

Each key defaults to the course's wiring on the calibration's arm (:attr:`ur3hanoi.robot.registry.RobotDescription.
course_suction_io`: the UR3 lab manual's Digital Input 0 / Analog Input 0 with digital output 0, unverified; the
UR3e course bridge's digital output 1, digital input 0, analog input 0). The course's own topics (``ur3/command``'s
``io_0``, ``gripper_input``) do not use it: their drivers map the pins themselves.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from ur3hanoi.io.schema import Field, Number, Record
from ur3hanoi.robot.registry import RobotDescription

DIGITAL_PINS = 18
"""``set_io`` digital output pins and ``io_states`` digital inputs: 0..17."""
ANALOG_INPUTS = 2
"""Standard analog inputs in ``io_states``: 0..1."""


@dataclass(frozen=True)
class SuctionWiring:
    """The suction's pins: the output switching it, the vacuum switch's digital input, the sensor's analog input."""

    output: int
    switch_input: int
    sensor_input: int

    def as_dict(self) -> dict[str, int]:
        """The ``io:`` section of a calibration file."""
        return {"suction_output": self.output, "vacuum_switch_input": self.switch_input,
                "vacuum_sensor_input": self.sensor_input}


def course_wiring(robot: RobotDescription) -> SuctionWiring:
    """The course's wiring on ``robot`` (see the module docstring)."""
    return SuctionWiring(*robot.course_suction_io)


IO_SECTION = Record({
    "suction_output": Field(Number(0, DIGITAL_PINS - 1, integer=True), required=False),
    "vacuum_switch_input": Field(Number(0, DIGITAL_PINS - 1, integer=True), required=False),
    "vacuum_sensor_input": Field(Number(0, ANALOG_INPUTS - 1, integer=True), required=False),
})
"""The schema of a calibration file's ``io:`` section (a part of ``STATION_SCHEMA``)."""


def parse_wiring(section: Mapping[str, Any] | None, robot: RobotDescription) -> SuctionWiring:
    """The wiring of a (schema-checked) ``io`` section; absent keys from the course's wiring on ``robot``."""
    default = course_wiring(robot)
    if section is None:
        return default
    return SuctionWiring(int(section.get("suction_output", default.output)),
                         int(section.get("vacuum_switch_input", default.switch_input)),
                         int(section.get("vacuum_sensor_input", default.sensor_input)))


__all__ = ["IO_SECTION", "SuctionWiring", "course_wiring", "parse_wiring"]
