"""Every numeric command-line option with its valid range, parsed and checked in this one place.

Each option's range is a :class:`~ur3hanoi.io.number.Number` (the same range type the input files use), so the
message says what is allowed, e.g. ``argument --rate: '1e-9' is invalid: expected a sample rate [Hz] in [1,
10000]``. Cross-option checks that need the station (blocks against the grid, the size of a plan) are here too.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable

from ur3hanoi.errors import Ur3HanoiError, quote
from ur3hanoi.io.limits import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.io.number import Number


class UsageError(Ur3HanoiError):
    """A command-line option is missing, invalid, or inconsistent with another one (exit code 2)."""


TABLE_KEYS: tuple[str, ...] = ("sim_pos", "real_pos")
"""The lab file's table keys for ``--key``: :data:`ur3hanoi.tables.TABLE_KEYS` spelt out, so that building the
parser does not load numpy (tests/cli/test_startup.py checks that both are the same)."""

MAX_BLOCKS = 10
"""Most blocks a plan or a solve takes (1023 moves)."""

MAX_PLAN_SAMPLES = 5_000_000
"""Most trajectory samples a plan may hold (about 1 GB), estimated before planning (see :func:`check_plan_size`)."""

SECONDS_PER_MOVE = 8.0
"""Upper estimate of one move's motion time [s] at full speed (the lab's moves take 5-6 s), for the estimate."""

SPEED = Number(0.01, 1.0, what="a fraction of the joint speed, acceleration and jerk limits")
RATE = Number(1.0, 10000.0, unit="Hz", what="a sample rate")
DWELL = Number(0.0, 10.0, unit="s", what="a dwell time")
SEED = Number(0, 2**32 - 1, integer=True, what="a seed")
TOL_MM = Number(0.0, 1000.0, lo_open=True, unit="mm", what="a position tolerance")
TOL_DEG = Number(0.0, 180.0, lo_open=True, unit="deg", what="an orientation tolerance")
TOWER = Number(1, MAX_TOWERS, integer=True, what="a tower number (1-based)")
BLOCKS = Number(1, MAX_BLOCKS, integer=True, what="a number of blocks")
HEIGHT = Number(1, MAX_HEIGHTS, integer=True, what="a height (1-based)")
MOVE = Number(1, 2**MAX_BLOCKS - 1, integer=True, what="a move number (1-based)")
FPS = Number(1.0, 120.0, unit="Hz", what="a frame rate")  # at most one frame per 125 Hz control cycle
IMAGE_SIDE = Number(16, 4096, integer=True, unit="px", what="an image side")
SIM_TIME = Number(0.0, 1e6, unit="s", what="a sim time")
# ROS commands (ros-station, ros-solve).
ROS_RATE = Number(50.0, 500.0, unit="Hz", what="a control and publishing rate")
CMD_SPEED = Number(0.0, 10.0, lo_open=True, unit="rad/s", what="a commanded joint speed (the driver caps it)")
CMD_ACCELERATION = Number(0.0, 20.0, lo_open=True, unit="rad/s^2",
                          what="a commanded joint acceleration (the driver caps it)")
GRASP_TIMEOUT = Number(0.0, 10.0, lo_open=True, unit="s", what="a wait for the vacuum switch")
DURATION = Number(0.0, 7 * 86400.0, lo_open=True, unit="s", what="a run time")
SPEED_SLIDER = Number(0.0, 1.0, lo_open=True, what="a speed slider fraction")
# teach.
DRIVER_WAIT = Number(0.5, 600.0, unit="s", what="a wait for the driver")

_MAX_TEXT = 40  # longer option values are not numbers anyone means (and int() of 5000 digits is refused anyway)


def _parse(text: str, integer: bool) -> float | int | None:
    text = text.strip()
    if not text or len(text) > _MAX_TEXT:
        return None
    try:
        return int(text, 10) if integer else float(text)
    except ValueError:
        return None


def option(spec: Number) -> Callable[[str], float | int]:
    """An argparse ``type=`` that parses a number and checks it against ``spec``."""

    def parse(text: str) -> float | int:
        value = _parse(text, spec.integer)
        if value is None or not spec.accepts(value):
            raise argparse.ArgumentTypeError(f"{quote(text)} is invalid: expected {spec.expected()}")
        return value

    parse.__name__ = spec.what or "number"
    return parse


def station_number(what: str) -> Callable[[str], int]:
    """An argparse ``type=`` for a tower, height or move number whose range is the station's or the instance's:
    any integer here, checked once the station is loaded (:func:`check_number`), so the message gives the range
    that applies (``--start 0`` on a 3-tower station: 1..3)."""

    def parse(text: str) -> int:
        value = _parse(text, integer=True)
        if value is None:
            raise argparse.ArgumentTypeError(f"{quote(text)} is invalid: expected {what}, an integer")
        return int(value)

    parse.__name__ = what
    return parse


def slot(text: str) -> tuple[int, int]:
    """An argparse ``type=`` for ``TOWER,HEIGHT`` (1-based, e.g. ``2,1``); the ranges are the station's, checked once
    it is loaded (:func:`check_number`)."""
    parts = text.split(",")
    values = [_parse(p, integer=True) for p in parts] if len(parts) == 2 else []
    if len(values) != 2 or any(v is None for v in values):
        raise argparse.ArgumentTypeError(f"{quote(text)} is invalid: expected TOWER,HEIGHT, e.g. 2,1 (tower 2, "
                                         "height 1; numbered from 1)")
    return int(values[0]), int(values[1])  # type: ignore[arg-type]


ACCEPT_HELP = ("accept the contact pose taught at tower T height H on your word (repeatable): it is never left out "
               "and its tower is placed where it says even off the other towers' level or axis (a tower that "
               "really stands apart); the output says so")
"""``--accept``'s help, one text for ``calibrate`` and ``teach``."""


def check_accept(accept: list[tuple[int, int]] | None, contacts: set[tuple[int, int]], where: str
                 ) -> set[tuple[int, int]]:
    """The ``--accept T,H`` slots (1-based) as 0-based ``(tower, height)``; each must name a contact pose taught in
    ``where`` (``contacts``: its taught contact slots, 0-based)."""
    out = set()
    for t, h in accept or ():
        if (t - 1, h - 1) not in contacts:
            taught = ", ".join(f"{a + 1},{b + 1}" for a, b in sorted(contacts)) or "none"
            raise UsageError(f"--accept {t},{h} is invalid: no contact pose is taught at tower {t} height {h} in "
                             f"{where} (taught: {taught})")
        out.add((t - 1, h - 1))
    return out


def check_number(option_name: str, value: int | None, hi: int, what: str, why: str = "") -> None:
    """``value`` (1-based) of ``option_name`` must be in 1..``hi``; ``why`` says where the bound comes from."""
    if value is not None and not 1 <= value <= hi:
        raise UsageError(f"{option_name} {value} is invalid: expected {what} 1..{hi}{f' ({why})' if why else ''}")


def image_size(text: str) -> tuple[int, int]:
    """An argparse ``type=`` for ``WxH`` [px]: two integers in :data:`IMAGE_SIDE`, both even (H.264/VP9 video
    needs even sides; PNG frames follow the same rule so one size works for both)."""
    parts = text.strip().lower().split("x")
    sides = [_parse(p, integer=True) for p in parts] if len(parts) == 2 else []
    if len(sides) != 2 or not all(v is not None and IMAGE_SIDE.accepts(v) and v % 2 == 0 for v in sides):
        raise argparse.ArgumentTypeError(f"{quote(text)} is invalid: expected WIDTHxHEIGHT, e.g. 640x480, each "
                                         f"an even number of pixels in [{IMAGE_SIDE.lo:g}, {IMAGE_SIDE.hi:g}]")
    return int(sides[0]), int(sides[1])  # type: ignore[arg-type]


def check_window(t_from: float | None, t_to: float | None) -> None:
    """The render window ``--from``/``--to`` [s] must not be empty (``--from`` defaults to 0)."""
    if t_to is not None and not t_to > (t_from or 0.0):
        raise UsageError(f"--to {t_to:g} is invalid: expected a time after --from ({t_from or 0.0:g} s)")


def check_blocks(n_blocks: int, n_heights: int, given: bool) -> None:
    """``n_blocks`` (``--blocks``, or the grid's heights when not ``given``) must be 1..MAX_BLOCKS."""
    if not 1 <= n_blocks <= MAX_BLOCKS:
        if given:
            raise UsageError(f"--blocks {n_blocks} is invalid: expected {BLOCKS.expected()}")
        raise UsageError(f"the calibration's grid has {n_heights} heights, more blocks than a plan takes "
                         f"(at most {MAX_BLOCKS}): choose fewer with --blocks")


def check_faults(remove_block: int | None, drop_during_move: int | None, n_blocks: int) -> None:
    """The fault injections must name a height and a move of this instance (1-based)."""
    n_moves = 2**n_blocks - 1
    check_number("--remove-block", remove_block, n_blocks, "a height", f"{n_blocks} blocks are spawned")
    check_number("--drop-during-move", drop_during_move, n_moves, "a move", f"{n_blocks} blocks take {n_moves} moves")


def check_plan_size(n_blocks: int, speed: float, dwell_s: float, rate_hz: float) -> None:
    """Refuse a plan whose samples would not fit in memory, before planning it.

    The estimate is ``moves x (SECONDS_PER_MOVE / speed + 2 dwell) x rate``, an upper bound for the lab's grids.
    """
    n_moves = 2**n_blocks - 1
    estimate = n_moves * (SECONDS_PER_MOVE / speed + 2 * dwell_s) * rate_hz
    if estimate > MAX_PLAN_SAMPLES:
        raise UsageError(f"{n_blocks} blocks at --speed {speed:g} and {rate_hz:g} Hz would make about "
                         f"{estimate:.3g} samples, more than {MAX_PLAN_SAMPLES}: use fewer blocks, a higher "
                         "--speed or a lower rate")
