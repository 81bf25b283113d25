"""A station as a student sets it up, for the tests and the bench of the first session on the official UR driver:
every tower put down by hand, tens of millimetres from where the base calibration puts it and each by its own amount,
the row turned as well (not a shifted copy of a shipped station), and a scripted operator that teaches it through
``teach --driver ur``'s pseudo-terminal with teach's own keys (the operator of tests/support/teach_operator.py).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tests.support.teach_operator import Operator
from ur3hanoi.io.resources import station_file
from ur3hanoi.station.calibration import Station, load_station

TOWER_MOVES_MM = ((21.0, -17.0, 0.0), (-14.0, 26.0, 0.0), (28.0, 12.0, 0.0))
"""[mm, world] how far each tower stands from where ``lab_real`` puts it, before the row is turned."""
ROW_TURN_DEG = 4.0
"""[deg] the row of towers turned about its centroid."""
ERRORS_MM = ((0.6, -0.4, 0.3), (-0.5, 0.5, 0.2), (0.4, 0.6, -0.3), (-0.3, -0.5, 0.4), (0.5, 0.3, 0.2),
             (-0.4, 0.4, -0.2))
"""[mm] the operator's deliberate error at each successive pose (a careful person's, about 1 mm)."""


def write_student_station(path: Path, base: str = "lab_real") -> Station:
    """``base`` with every tower moved by :data:`TOWER_MOVES_MM` and the row turned by :data:`ROW_TURN_DEG`;
    returns it as loaded."""
    data = yaml.safe_load(station_file(base).read_text())
    origins = np.array(data["grid"]["tower_origins"], dtype=float)
    moved = origins + np.array(TOWER_MOVES_MM) * 1e-3
    centre = moved.mean(axis=0)
    c, s = math.cos(math.radians(ROW_TURN_DEG)), math.sin(math.radians(ROW_TURN_DEG))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    moved = (moved - centre) @ R.T + centre
    data["name"] = "student"
    data["grid"]["tower_origins"] = [[round(float(v), 7) for v in p] for p in moved]
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return load_station(path)


def teach_session(child: Any, base: Station, hidden: Station, suction_at: int = 0,
                  max_poses: int = 12) -> dict[str, Any]:
    """Teach every pose the guidance names, through teach's pseudo-terminal ``child``: ``g``, jog to the hidden
    contact (plus :data:`ERRORS_MM`), Enter; at pose ``suction_at`` also ``v`` (suction on: the block must be held)
    and ``v`` again (off); then ``f`` (after ``max_poses`` poses at the latest). Returns what the operator saw: the
    poses taught, the suction lines."""
    op = Operator(child, base, hidden)
    seen: dict[str, Any] = {"poses": [], "suction": []}
    op.expect(r"next: [^\n]*\n")
    named = child.after
    for i in range(max_poses):
        match = re.search(r"next: tower (\d) height (\d)", named)
        if match is None:
            break
        t, h = int(match.group(1)) - 1, int(match.group(2)) - 1
        op.go(t, h)
        op.move_to(t, h, ERRORS_MM[i % len(ERRORS_MM)])
        if i == suction_at:
            for _ in range(2):
                child.send("v")
                seen["suction"].append(op.expect(r"suction (on|off)[^\r\n]*").group(0).strip())
        named = op.record(f"tower {t + 1} height {h + 1}")
        seen["poses"].append([t + 1, h + 1])
    child.send("f")
    return seen


__all__ = ["ERRORS_MM", "ROW_TURN_DEG", "TOWER_MOVES_MM", "teach_session", "write_student_station"]


def main() -> int:
    """``python -m tests.support.student_cell DIR N [TEACH OPTIONS...]``: teach (through a pseudo-terminal) the station
    of ``DIR/student.yaml`` at most N poses, with ``teach --base lab_real -o DIR/taught.yaml --table
    DIR/lab2_data.yaml --station-out DIR/station.yaml TEACH OPTIONS``; writes ``DIR/transcript.txt`` and prints what
    the operator saw as one JSON line (the exit status in it, the wall time [s] until ``f`` and from ``f`` to
    teach's end: the calibration and the table written)."""
    import json
    import sys
    import time

    import pexpect

    from tests.support.teach_operator import screen_text

    folder, n, extra = Path(sys.argv[1]), int(sys.argv[2]), sys.argv[3:]
    argv = ["-m", "ur3hanoi.cli", "teach", "--base", "lab_real", "-o", str(folder / "taught.yaml"), "--table",
            str(folder / "lab2_data.yaml"), "--station-out", str(folder / "station.yaml"), *extra]
    with (folder / "raw.txt").open("w") as raw:
        t0 = time.perf_counter()
        child = pexpect.spawn(sys.executable, argv, encoding="utf-8", dimensions=(30, 150), timeout=60)
        child.logfile_read = raw
        try:
            seen = teach_session(child, load_station("lab_real"), load_station(folder / "student.yaml"),
                                 max_poses=n)
            t1 = time.perf_counter()
            child.expect(pexpect.EOF, timeout=180)
        finally:
            child.close(force=True)
    seen.update(exit=child.exitstatus, teach_s=round(t1 - t0, 2), finish_s=round(time.perf_counter() - t1, 2))
    (folder / "transcript.txt").write_text(screen_text((folder / "raw.txt").read_bytes().decode()))
    print(json.dumps(seen))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
