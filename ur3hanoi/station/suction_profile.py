"""Suction feedback profiles: what ``gripper_input`` (``DIGIN``, ``AIN0``) reads when a block is held, when the
suction is on with the cup free, and when it is off.

The lab's vacuum generator (a Coval unit, lab manual section 2.6) drives the robot's digital input 0 (a vacuum
switch) and analog input 0 (the vacuum sensor's voltage). Student programs decide "block held" from either. The
levels differ between the course's Gazebo simulator and real stations, so a station calibration says which it has
(``suction:`` section, see ``ur3hanoi/station/shipped/README.md``):

- ``lab_sim``: the course simulator's values (``../shared/lab/ros-interface.md``): about 1.9 V held, 1.45 V cup
  free, 1.05 V off. The default of every station without a ``suction`` section.
- ``real``: levels consistent with what programs written on the real robot expect. Public student programs
  detect a missing block with ``AIN0 < t`` after lifting, with ``t`` = 1.75, 1.8, 1.95 and 2.0 V: thresholds
  calibrated on real stations, so a held block reads above 2.0 V and a free cup below 1.75 V there. The profile
  puts the held level 2.35 V and the free level 1.40 V, symmetric about the middle of that threshold band
  (1.875 V) and 0.35 V clear of its ends: 17 standard deviations of its 0.02 V noise, so no program with a
  threshold in the band ever reads a false "missing" or "held". Off stays the simulator's 1.05 V (no vacuum at
  all). These are a consistent stand-in, not a measurement: measure your station's own levels and set them
  (the manual's page "Suction feedback profiles", ``docs/suction.md``).

Nothing here imports MuJoCo: the calibration (:mod:`ur3hanoi.station.calibration`) carries a profile, and the suction
model (:mod:`ur3hanoi.sim.suction`) reads it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from ur3hanoi.io.schema import Choice, Field, Number, Record

AIN_RANGE_V: tuple[float, float] = (0.0, 10.0)
"""The UR controller's analog inputs read 0..10 V."""
MAX_NOISE_V = 1.0
"""Largest accepted standard deviation of the ``AIN0`` noise [V]."""
DIGIN_MAX = 255
"""``DIGIN`` levels are the tool/controller digital input byte: 0..255 (bit 0 = vacuum switch)."""


@dataclass(frozen=True)
class SuctionProfile:
    """What the suction feedback reads in each state.

    Attributes:
        name: profile name (``lab_sim``, ``real``, or ``custom`` when levels were given explicitly).
        ain0_held, ain0_free, ain0_off: ``AIN0`` [V] with a block held, suction on with the cup free, suction off.
        digin_held, digin_free, digin_off: ``DIGIN`` in the same three states (bit 0 = the vacuum switch).
        ain0_noise: standard deviation [V] of the seeded Gaussian noise added to every ``AIN0`` sample.
    """

    name: str
    ain0_held: float
    ain0_free: float
    ain0_off: float
    ain0_noise: float
    digin_held: int = 1
    digin_free: int = 0
    digin_off: int = 0

    def levels(self, held: bool, on: bool) -> tuple[int, float]:
        """(``DIGIN``, noiseless ``AIN0`` [V]) for a state: held (implies on), on with the cup free, or off."""
        if held:
            return self.digin_held, self.ain0_held
        if on:
            return self.digin_free, self.ain0_free
        return self.digin_off, self.ain0_off

    def as_dict(self) -> dict[str, Any]:
        """The profile for reports and calibration files (every level explicit)."""
        return {"profile": self.name, "ain0_held": self.ain0_held, "ain0_free": self.ain0_free,
                "ain0_off": self.ain0_off, "ain0_noise": self.ain0_noise, "digin_held": self.digin_held,
                "digin_free": self.digin_free, "digin_off": self.digin_off}


LAB_SIM = SuctionProfile(name="lab_sim", ain0_held=1.9, ain0_free=1.45, ain0_off=1.05, ain0_noise=0.01)
REAL = SuctionProfile(name="real", ain0_held=2.35, ain0_free=1.40, ain0_off=1.05, ain0_noise=0.02)

PROFILES: dict[str, SuctionProfile] = {p.name: p for p in (LAB_SIM, REAL)}
"""The named profiles (see the module docstring)."""
DEFAULT_PROFILE = LAB_SIM
CUSTOM = "custom"
"""The name of a profile whose levels were set explicitly."""

LEVEL_KEYS: tuple[str, ...] = ("ain0_held", "ain0_free", "ain0_off", "ain0_noise", "digin_held", "digin_free",
                               "digin_off")


def profile_named(name: str) -> SuctionProfile:
    """The named profile; ``KeyError`` names the valid ones (the CLI and the schema check names first)."""
    try:
        return PROFILES[name]
    except KeyError:
        raise KeyError(f"suction profile {name!r} is unknown: expected one of {', '.join(PROFILES)}") from None


def with_levels(base: SuctionProfile, levels: dict[str, Any]) -> SuctionProfile:
    """``base`` with some levels replaced (``levels`` keys from :data:`LEVEL_KEYS`); named ``custom`` if any is."""
    changes: dict[str, Any] = {}
    for key, value in levels.items():
        if key not in LEVEL_KEYS:
            raise KeyError(f"suction level {key!r} is unknown: expected one of {', '.join(LEVEL_KEYS)}")
        changes[key] = int(value) if key.startswith("digin") else float(value)
    if not changes:
        return base
    out = replace(base, **changes)
    return out if out == base else replace(out, name=CUSTOM)


SUCTION_SECTION = Record({
    "profile": Field(Choice(tuple(PROFILES)), required=False),
    **{key: Field(Number(0, DIGIN_MAX, integer=True), required=False) for key in LEVEL_KEYS
       if key.startswith("digin")},
    **{key: Field(Number(*AIN_RANGE_V, unit="V", what="a voltage"), required=False) for key in LEVEL_KEYS
       if key.startswith("ain0") and key != "ain0_noise"},
    "ain0_noise": Field(Number(0.0, MAX_NOISE_V, unit="V", what="a standard deviation"), required=False),
})
"""The schema of a calibration file's ``suction:`` section (a part of ``STATION_SCHEMA``)."""


def parse_suction(section: Mapping[str, Any] | None) -> SuctionProfile:
    """The suction profile of a (schema-checked) ``suction`` section: a named profile (default ``lab_sim``)
    with any explicitly given levels replacing its own (the result is then named ``custom``)."""
    if section is None:
        return DEFAULT_PROFILE
    base = PROFILES[section["profile"]] if "profile" in section else DEFAULT_PROFILE
    return with_levels(base, {k: v for k, v in section.items() if k != "profile"})


def suction_section(p: SuctionProfile) -> dict[str, Any]:
    """``p`` as a calibration file's ``suction:`` section: a named profile by its name; a custom one as every
    level over the default profile."""
    if PROFILES.get(p.name) == p:
        return {"profile": p.name}
    return {k: v for k, v in p.as_dict().items() if k != "profile"}


__all__ = [
    "AIN_RANGE_V",
    "CUSTOM",
    "DEFAULT_PROFILE",
    "DIGIN_MAX",
    "LAB_SIM",
    "LEVEL_KEYS",
    "MAX_NOISE_V",
    "PROFILES",
    "REAL",
    "SUCTION_SECTION",
    "SuctionProfile",
    "parse_suction",
    "profile_named",
    "suction_section",
    "with_levels",
]
