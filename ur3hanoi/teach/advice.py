"""Which pose to record next, and why.

1. **Required**: the fit needs a contact on every tower. Tower by tower, the one with the blocks (``start``) is
   taught on its top block (the ones below are covered), the others on a block on the table (height 1) for a
   stacked station; a flat station's first row on every tower.
2. **A checked set**, once every tower has one: a tower resting on one pose may stand anywhere along the table (a
   joint-1 offset moves it unseen: issue 37), so each such tower is named next for a second height, until every
   tower is checked by a second pose (``f`` writes before that, saying which towers rest on one pose). Then, as
   options, the slot that makes the most points checkable (:func:`ur3hanoi.calibrate.grid_fit.removable`; the
   audit calls the others ``unchecked``); then the tower with the fewest points; then the height farthest from the
   tower's taught ones (the longest lever for the step between levels).

A slot skipped (``s``) is not named again in the session.
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass

from ur3hanoi.calibrate.grid_fit import choose_model, removable
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON
from ur3hanoi.tables import Slot


@dataclass(frozen=True)
class Advice:
    """The pose to record next: ``tower``, ``height`` (0-based), whether the fit ``required`` it, and ``why``."""

    tower: int
    height: int
    required: bool
    why: str

    @property
    def label(self) -> str:
        return f"tower {self.tower + 1} height {self.height + 1}"


def _checkable(base: Station, slots: Sequence[Slot]) -> int:
    model = choose_model(base, slots)
    return 0 if model is None else int(removable(model, slots).sum())


def _towers(towers: Sequence[int]) -> str:
    return " and ".join(", ".join(str(t + 1) for t in towers).rsplit(", ", 1))


def _where(base: Station, tower: int, height: int, start: int) -> str:
    """What has to be there to touch the slot (stacked stations)."""
    if base.layout != "stacked":
        return ""
    if tower == start:
        top = base.n_heights - 1
        return (" (the top block of the stack)" if height == top else
                f" (take the {top - height} block(s) above it off first)" if height < top else "")
    return " (a block on the table)" if height == 0 else f" (stack {height + 1} blocks there first)"


def required_height(base: Station, tower: int, start: int) -> int:
    """The height taught on ``tower`` when it has none: the top of the stack on ``start``, else the bottom."""
    return base.n_heights - 1 if base.layout == "stacked" and tower == start else 0


def next_pose(base: Station, slots: Sequence[Slot], start: int, skipped: Collection[tuple[int, int]] = ()
              ) -> Advice | None:
    """The pose to name next, given the slots taught (0-based ``(tower, height, k)``), the tower holding the blocks
    (``start``, 0-based) and the ``(tower, height)`` slots skipped; None when nothing is left to suggest."""
    taught_on = [(t, h) for t, h, k in slots if k == ON]
    bare = [t for t in range(base.n_towers) if all(tt != t for tt, _ in taught_on)]
    for t in bare:
        h = required_height(base, t, start)
        if (t, h) not in skipped:
            return Advice(t, h, True, f"the fit needs a contact on every tower: tower(s) {_towers(bare)} have none "
                                      f"yet{_where(base, t, h, start)}")
    if bare:
        return None  # the required poses left were skipped: nothing else checks anything without them
    n_now = _checkable(base, list(slots))
    candidates = [(t, h) for t in range(base.n_towers) for h in range(base.n_heights)
                  if (t, h) not in taught_on and (t, h) not in skipped]
    if not candidates:
        return None

    single = [t for t in range(base.n_towers) if sum(1 for tt, _, _ in slots if tt == t) == 1]

    def rank(c: tuple[int, int]) -> tuple[bool, int, int, int, int, int]:
        t, h = c
        gain = _checkable(base, [*slots, (t, h, ON)]) - n_now
        on_tower = [hh for tt, hh in taught_on if tt == t]
        lever = min(abs(h - hh) for hh in on_tower) if on_tower else 0
        return (t not in single, -gain, len(on_tower), -lever, t, h)

    t, h = min(candidates, key=rank)
    gain = -rank((t, h))[1]
    n = len(slots)
    if t in single:
        rest = [u for u in single if u != t]
        more = f" (then tower(s) {_towers(rest)})" if rest else ""
        why = (f"tower {t + 1} rests on one pose: nothing checks where it stands along the table (a joint-1 offset "
               f"would move it unseen); a second height checks it{more}. f writes without it, with that note")
    elif n_now == n:
        why = "optional: every point is checked by the others; more points average the recording noise"
    elif gain > 0:
        why = (f"optional: {n - n_now} of the {n} points cannot be checked yet (each alone fixes its tower or the step "
               f"between levels: the audit calls them unchecked); this one makes {gain} more checkable")
    else:
        why = (f"optional: {n - n_now} of the {n} points cannot be checked yet; every tower taught at two heights "
               "checks them all, and this is a step towards it")
    return Advice(t, h, False, why + _where(base, t, h, start))  # optional: f writes without it


__all__ = ["Advice", "next_pose", "required_height"]
