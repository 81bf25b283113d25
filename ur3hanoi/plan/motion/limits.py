"""The per-joint limits a plan is made under (its own module so that the motion modules need nothing else of
:mod:`ur3hanoi.plan.types`, which refers back to them)."""

from __future__ import annotations

from dataclasses import dataclass

from ur3hanoi.arrays import FloatArray


@dataclass(frozen=True)
class KinematicLimits:
    """Per-joint limits used for planning [rad/s, rad/s^2, rad/s^3], already scaled by ``PlanConfig.speed``."""

    v_max: FloatArray
    a_max: FloatArray
    j_max: FloatArray
