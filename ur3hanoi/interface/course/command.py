"""Validation of ``ur3/command`` messages: what the station executes and what it refuses.

A real controller refuses a joint move it cannot execute; so does the station, with a logged error and no motion:
a destination that is not exactly 6 finite joint angles inside the joint limits, or a speed/acceleration that is
not a finite positive number. Valid speeds and accelerations above the UR3's limits are accepted and capped per
joint (:mod:`ur3hanoi.robot.movej`), as the course drivers clamp them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from ur3hanoi.interface.common.errors import CommandError
from ur3hanoi.robot.model import JointLimits
from ur3hanoi.robot.registry import N_JOINTS


@dataclass(frozen=True)
class MoveCommand:
    """An accepted command: ``destination`` [rad, controller convention], ``v`` [rad/s], ``a`` [rad/s^2] as sent
    (capped only when executed) and the suction output ``io_0``."""

    destination: tuple[float, ...]
    v: float
    a: float
    io_0: bool

    def as_dict(self) -> dict[str, object]:
        return {"destination": [round(x, 9) for x in self.destination], "v": self.v, "a": self.a,
                "io_0": self.io_0}


def _finite_positive(name: str, value: object, unit: str) -> float:
    try:
        x = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise CommandError(f"{name} = {value!r} is invalid: expected a finite number > 0 [{unit}]") from None
    if not math.isfinite(x) or x <= 0.0:
        raise CommandError(f"{name} = {x!r} is invalid: expected a finite number > 0 [{unit}]")
    return x


def parse_command(destination: Sequence[float], v: object, a: object, io_0: object,
                  limits: JointLimits) -> MoveCommand:
    """Check one ``ur3/command`` message.

    Raises:
        CommandError: naming the bad field and value and what is valid (6 angles within ``limits``, v > 0, a > 0).
    """
    n = len(destination)  # before copying: a flood of huge arrays must cost nothing but their refusal
    if n != N_JOINTS:
        raise CommandError(f"destination has {n} values: expected {N_JOINTS} joint angles [rad]")
    values = list(destination)
    q = []
    for i, raw in enumerate(values):
        try:
            x = float(raw)
        except (TypeError, ValueError):
            raise CommandError(f"destination[{i}] = {raw!r} is invalid: expected a finite angle [rad]") from None
        if not math.isfinite(x):
            raise CommandError(f"destination[{i}] = {x!r} is invalid: expected a finite angle [rad]")
        lo, hi = limits.q_min[i], limits.q_max[i]
        if not lo <= x <= hi:
            raise CommandError(f"destination[{i}] = {x!r} rad is outside joint {i + 1}'s limits: expected "
                               f"{lo:.6g} <= q <= {hi:.6g} rad")
        q.append(x)
    return MoveCommand(tuple(q), _finite_positive("v", v, "rad/s"), _finite_positive("a", a, "rad/s^2"),
                       bool(io_0))
