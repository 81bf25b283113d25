"""Which table entries a Hanoi solve visits, and the one rule every table follower applies: entries the solve
visits must be present, entries it never visits may be missing.

``ur3hanoi solve --table`` (through :func:`ur3hanoi.plan.plan_table`) and ``ur3hanoi ros-solve --table`` (through
:meth:`ur3hanoi.tables.RecordedTable.for_solve`) both apply :func:`require_entries`, so they accept and refuse
the same tables.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError, printable
from ur3hanoi.hanoi import Move
from ur3hanoi.station.grid import ABOVE, ON, POSE_NAMES

Entry = tuple[int, int, int]
"""``(tower, height, k)``, 0-based as the file indexes the table."""


def entry_label(tower: int, height: int, k: int) -> str:
    """``"tower 1 height 3 on (Q[0][2][0])"``: 1-based for people, with the file's 0-based list index."""
    return f"tower {tower + 1} height {height + 1} {POSE_NAMES[k]} (Q[{tower}][{height}][{k}])"


def entries_visited(moves: Sequence[Move]) -> list[Entry]:
    """The table entries a move sequence visits, in order of first visit (on and above of every source and
    destination slot)."""
    seen: dict[Entry, None] = {}
    for m in moves:
        for t, h in ((m.from_tower, m.from_height), (m.to_tower, m.to_height)):
            seen.setdefault((t, h, ABOVE))
            seen.setdefault((t, h, ON))
    return list(seen)


def missing_entries(table: FloatArray, moves: Sequence[Move]) -> list[Entry]:
    """The entries ``moves`` visit that ``table`` (T, H, 2, 6) lacks (any NaN joint), sorted by index."""
    return sorted(e for e in entries_visited(moves) if not np.all(np.isfinite(table[e])))


def require_entries(table: FloatArray, moves: Sequence[Move], where: str = "table") -> None:
    """Raise :class:`TableError` naming every entry ``moves`` visit that ``table`` lacks."""
    missing = missing_entries(table, moves)
    if missing:
        names = "; ".join(entry_label(*e) for e in missing)
        raise TableError(f"{printable(where)}: {len(missing)} table "
                         f"entr{'y' if len(missing) == 1 else 'ies'} the solve needs "
                         f"{'is' if len(missing) == 1 else 'are'} missing: {names}")


__all__ = ["Entry", "entries_visited", "entry_label", "missing_entries", "require_entries"]
