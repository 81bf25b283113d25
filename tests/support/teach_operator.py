"""A scripted operator of ``ur3hanoi teach``: types into its pseudo-terminal as a person does (pexpect), and the
hidden station it teaches (``lab_real``'s grid moved by several mm and turned by 2 deg, written to a file the
station loads with ``--calibration``).

The operator knows where the hidden blocks are (a person sees them); teach does not. To reach a contact it presses
``g`` (teach moves above where the base calibration puts the named pose), then jogs with teach's own keys: the
fewest 20 / 5 / 1 mm steps per axis that reach the hidden contact plus a deliberate error, so the pose it records
is off by that error and at most 0.5 mm per axis (the 1 mm jog resolution).
"""

from __future__ import annotations

import itertools
import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from ur3hanoi.io.resources import station_file
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, H_world_tcp, contact_point_world

HIDDEN_TURN_DEG = 2.0
HIDDEN_SHIFT_M = (0.005, -0.004, 0.001)
STEP_KEYS = {1: "1", 5: "2", 20: "3"}
AXIS_KEYS = ("x", "y", "z")
JOG_RESOLUTION_MM = 1.0


def write_hidden_station(path: Path) -> Station:
    """``lab_real`` with its tower grid turned by :data:`HIDDEN_TURN_DEG` about the towers' centroid and moved by
    :data:`HIDDEN_SHIFT_M`; returns it as loaded."""
    data = yaml.safe_load(station_file("lab_real").read_text())
    origins = np.array(data["grid"]["tower_origins"], dtype=float)
    centre = origins.mean(axis=0)
    c, s = math.cos(math.radians(HIDDEN_TURN_DEG)), math.sin(math.radians(HIDDEN_TURN_DEG))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    moved = (origins - centre) @ R.T + centre + np.array(HIDDEN_SHIFT_M)
    data["name"] = "hidden"
    data["grid"]["tower_origins"] = [[round(float(v), 7) for v in p] for p in moved]
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_station(path)


def steps_for(delta_mm: float) -> list[int]:
    """The fewest signed 20 / 5 / 1 mm steps whose sum is ``delta_mm`` rounded to whole mm."""
    k = round(delta_mm)
    best: list[int] | None = None
    for a, b in itertools.product(range(round(k / 20) - 1, round(k / 20) + 2), range(-4, 5)):
        c = k - 20 * a - 5 * b
        steps = [20 * int(math.copysign(1, a))] * abs(a) + [5 * int(math.copysign(1, b))] * abs(b) + \
            [int(math.copysign(1, c))] * abs(c)
        if best is None or len(steps) < len(best):
            best = steps
    assert best is not None and sum(best) == k
    return best


class Operator:
    """Drives a spawned ``teach`` (a ``pexpect.spawn``) on a station whose true grid is ``hidden``."""

    def __init__(self, child: Any, base: Station, hidden: Station) -> None:
        self.child, self.base, self.hidden = child, base, hidden
        self.at_mm: np.ndarray | None = None
        self.step_mm = 5  # teach starts with the 5 mm step
        self.log: list[str] = []

    def expect(self, pattern: str, timeout: float = 30.0) -> re.Match[str]:
        self.child.expect(pattern, timeout=timeout)
        match: re.Match[str] = self.child.match
        return match

    def _key(self, key: str, done: str, timeout: float = 30.0) -> None:
        self.child.send(key)
        self.expect(done, timeout)

    def go(self, tower: int, height: int) -> None:
        """``g``: above the named pose (0-based slot) where the base puts it."""
        self._key("g", f"go above tower {tower + 1} height {height + 1}: done")
        self.at_mm = H_world_tcp(self.base, tower, height, ABOVE)[:3, 3] * 1e3

    def jog(self, axis: int, mm: int) -> None:
        size = abs(mm)
        if size != self.step_mm:
            self._key(STEP_KEYS[size], f"jog step {size} mm")
            self.step_mm = size
        key = AXIS_KEYS[axis] if mm > 0 else AXIS_KEYS[axis].upper()
        self._key(key, re.escape(f"jog {AXIS_KEYS[axis]} {mm:+d} mm: done"))
        assert self.at_mm is not None
        self.at_mm[axis] += mm

    def move_to(self, tower: int, height: int, error_mm: tuple[float, float, float]) -> np.ndarray:
        """Jog to the hidden contact of (tower, height) + ``error_mm``: x and y first, so that the last moves are the
        descent onto the block; returns where the suction point is [mm, world]."""
        target = contact_point_world(self.hidden, tower, height) * 1e3 + np.array(error_mm)
        assert self.at_mm is not None
        for axis in (0, 1, 2):
            for mm in steps_for(float(target[axis] - self.at_mm[axis])):
                self.jog(axis, mm)
        return self.at_mm.copy()

    def reach(self, tower: int, height: int, error_mm: tuple[float, float, float]) -> np.ndarray:
        """``g``, then :meth:`move_to`."""
        self.go(tower, height)
        return self.move_to(tower, height, error_mm)

    def wait_still(self) -> None:
        """Until the live status says the arm is still (as a person waits before pressing Enter)."""
        self.expect(r"\d\s+still")

    def record(self, label: str) -> str:
        """Wait until still, Enter, expecting ``recorded <label>``; returns the text up to the next named pose."""
        self.wait_still()
        self.child.send("\r")
        self.expect(f"recorded {label}")
        self.expect(r"next: [^\n]*\n")
        text: str = self.child.before + self.child.after
        return text


ERRORS_MM = ((0.7, -0.5, 0.4), (-0.6, 0.6, 0.3), (0.5, 0.7, -0.4))
"""The deliberate error of each good contact [mm] (about 1 mm, as a careful person jogs)."""
OFF_MM = (9.0, 0.0, 12.0)
"""The pose taught 15 mm off (then undone and taught again)."""


def practice_session(child: Any, base: Station, hidden: Station) -> dict[str, Any]:
    """The whole practice session on a running station, through teach's pseudo-terminal ``child``: three contacts
    (the third first 15 mm off: named as a suspect, undone, taught again), an Enter while a jog step runs (refused),
    a fourth pose recorded in the wrong slot (tower 3's, as tower 1 height 1: named at once, undone), then ``f``.
    Returns what the operator saw and did."""
    import pexpect

    op = Operator(child, base, hidden)
    seen: dict[str, Any] = {"at_mm": []}
    op.expect("next: tower 1 height 3")
    seen["at_mm"].append(op.reach(0, 2, ERRORS_MM[0]).tolist())
    op.record("tower 1 height 3")
    child.send("g")
    child.send("\r")  # at once: the arm is on its way above tower 2
    op.expect("the arm is moving")
    seen["moving_refused"] = True
    op.expect("go above tower 2 height 1: done")
    op.at_mm = H_world_tcp(base, 1, 0, ABOVE)[:3, 3] * 1e3
    seen["at_mm"].append(op.move_to(1, 0, ERRORS_MM[1]).tolist())
    op.record("tower 2 height 1")
    op.reach(2, 0, OFF_MM)
    seen["suspect"] = op.record("tower 3 height 1")
    child.send("u")
    op.expect("undone")
    seen["at_mm"].append(op.move_to(2, 0, ERRORS_MM[2]).tolist())
    seen["after"] = op.record("tower 3 height 1")
    # Teach names tower 1 height 1 next; Enter with the arm still on tower 3 records a pose in the wrong slot.
    seen["wrong_slot"] = op.record("tower 1 height 1")
    child.send("u")
    op.expect("undone")
    child.send("f")
    child.expect(pexpect.EOF, timeout=180)
    child.close()
    seen["exit"] = child.exitstatus
    return seen


def screen_text(raw: str) -> str:
    """A pseudo-terminal transcript as a person last saw it: the live status redraws (cursor up, clear) applied,
    carriage returns dropped (``raw`` as written: not read in text mode, which turns a lone carriage return into
    a line break)."""
    lines: list[str] = []
    current = ""
    i = 0
    while i < len(raw):
        m = re.match(r"\x1b\[(\d*)([AJ])", raw[i:])
        if m:
            if m.group(2) == "A":
                for _ in range(int(m.group(1) or 1)):
                    current = lines.pop() if lines else ""
            else:
                current = ""
            i += m.end()
            continue
        ch = raw[i]
        if ch == "\n":
            lines.append(current)
            current = ""
        elif ch == "\r":
            if not raw.startswith("\n", i + 1):  # a bare carriage return: the line is written over
                current = ""
        else:
            current += ch
        i += 1
    return "\n".join([*lines, current]).rstrip() + "\n"


def main() -> int:
    """``python -m tests.support.teach_operator DIR VIA [TEACH OPTIONS...]``: the practice session against a station
    that runs ``DIR/hidden.yaml``; writes ``DIR/transcript.txt`` and prints the session's outcome as one JSON line."""
    import json
    import sys

    import pexpect

    folder, via, extra = Path(sys.argv[1]), sys.argv[2], sys.argv[3:]
    hidden, base = load_station(folder / "hidden.yaml"), load_station("lab_real")
    argv = ["-m", "ur3hanoi.cli", "teach", "--via", via, "--base", "lab_real", "-o", str(folder / "taught.yaml"),
            "--table", str(folder / "lab2_data.yaml"), "--station-out", str(folder / "station.yaml"), *extra]
    with (folder / "raw.txt").open("w") as raw:
        child = pexpect.spawn(sys.executable, argv, encoding="utf-8", dimensions=(30, 150), timeout=60)
        child.logfile_read = raw
        try:
            seen = practice_session(child, base, hidden)
        finally:
            child.close(force=True)
    (folder / "transcript.txt").write_text(screen_text((folder / "raw.txt").read_bytes().decode()))
    print(json.dumps(seen))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
