"""What teach needs from the arm's driver, whatever the middleware: the positions it publishes with their arrival
times, a joint move sent at a speed of teach's own, whether it is ur3hanoi's simulated station (no pendant there),
and the problem of the last malformed position message.

:class:`ur3hanoi.interface.course.client.TopicArm` (on rospy or Cyclone DDS) is such a driver; the command line connects
one and passes it in. This module imports no middleware.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Protocol

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import DriverError

LOST_S = 2.0
"""[s] a driver that published no position for this long is gone (it publishes one every control cycle)."""


class Driver(Protocol):
    """A connected driver client (see the module docstring)."""

    malformed: str
    """What was wrong with the last position message that was not six finite angles ("" if none was)."""

    def samples(self, window_s: float) -> list[tuple[float, FloatArray]]:
        """The positions of the last ``window_s`` seconds: ``(time.monotonic() of arrival, q [rad, controller
        convention])``, oldest first."""
        ...

    def send(self, q: FloatArray, v: float, a: float) -> None:
        """Command a joint move to ``q`` [rad] at joint speed ``v`` [rad/s] and acceleration ``a`` [rad/s^2]."""
        ...

    def simulated(self) -> bool:
        """True for ur3hanoi's own station (``ros-station``, ``ros2-station``): there is no pendant."""
        ...


@dataclass(frozen=True)
class DriverNames:
    """How messages name the driver: ``where`` it runs (a master URI, a DDS domain), its ``position`` and
    ``command`` topics, and the ``solve`` command that drives it (``ros-solve``)."""

    where: str
    position: str
    command: str
    solve: str


def latest(driver: Driver, names: DriverNames) -> tuple[float, FloatArray]:
    """The newest position ``(arrival time [s], q [rad])``.

    Raises:
        DriverError: the driver published a malformed position, or none for :data:`LOST_S`.
    """
    if driver.malformed:
        raise DriverError(f"the driver on {names.where} published {driver.malformed} on {names.position}")
    recent = driver.samples(LOST_S)
    if not recent or time.monotonic() - recent[-1][0] > LOST_S:
        raise DriverError(f"the driver on {names.where} stopped: no {names.position} for {LOST_S:g} s")
    return recent[-1]


__all__ = ["LOST_S", "Driver", "DriverNames", "latest"]
