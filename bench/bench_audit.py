"""Benchmark (not a test): how often `check-table --fit` cries wolf on recorded-like tables, how often it names an
injected gross error first, and its wall time.

Recorded-like tables (tests/support/recorded_tables.py, `recorded_like`): 1-2 mm jitter, a heading per tower and wrist 3
turned per entry, a small table-wide tilt of the suction axis, above poses 15-60 mm over the top of the stacks;
stacked stations (lab_real robot, three towers 5-15 cm apart, uneven) and the flat Gazebo layout (lab_sim).

- false alarms: clean tables with any entry flagged (exit 1), and flagged entries over all entries;
- detection: tables where the injected entry is the first one named (10 deg on joint 1, 3 deg on joint 2, two
  heights swapped, a contact copied into another height, a suction axis tilted 5-6 deg);
- wall: `ur3hanoi check-table --fit` on one table (median of 5 runs).

Run: .venv/bin/python bench/bench_audit.py [--seeds 30]
"""

from __future__ import annotations

import argparse
import json
import math
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))

from tests.support import recorded_tables as rt  # noqa: E402
from ur3hanoi.audit import audit_table  # noqa: E402
from ur3hanoi.station.calibration import load_station  # noqa: E402
from ur3hanoi.station.grid import ON  # noqa: E402
from ur3hanoi.tables import read_recorded_table  # noqa: E402

ERRORS = ("typo-j1-10deg", "typo-j2-3deg", "swapped-heights", "duplicated", "tilt-5-6deg")


LEGACY = False  # --legacy: the older generator (recorded_q: 1-3 mm, 0-0.5 deg, no heading spread, one approach)


def clean(st, rng: np.random.Generator, tilted: tuple[int, int, int] | None = None) -> np.ndarray:
    if LEGACY:
        return rt.recorded_q(st, rng)
    return rt.recorded_like(st, rng, tilted=tilted).q


def inject(kind: str, st, rng: np.random.Generator) -> tuple[np.ndarray, list[tuple[int, int, int]]]:
    slot = (int(rng.integers(st.n_towers)), int(rng.integers(st.n_heights)), ON)
    other = (slot[0], (slot[1] + 1 + int(rng.integers(st.n_heights - 1))) % st.n_heights, ON)
    if kind == "tilt-5-6deg":
        return clean(st, rng, tilted=slot), [slot]
    q = clean(st, rng)
    sign = 1.0 if rng.random() < 0.5 else -1.0
    if kind == "typo-j1-10deg":
        return rt.typo(q, slot, 0, sign * 10.0), [slot]
    if kind == "typo-j2-3deg":
        return rt.typo(q, slot, 1, sign * 3.0), [slot]
    if kind == "swapped-heights":
        return rt.swap(q, slot, other), [slot, other]
    return rt.duplicate(q, slot, other), [other]


def audit(tmp: Path, q: np.ndarray, key: str):
    path = rt.write_table(tmp / "t.yaml", key, rt.table_doc(q))
    return audit_table(read_recorded_table(path, key), load_station("lab_sim" if key == "sim_pos" else "lab_real"))


def flagged(report) -> list[tuple[int, int, int]]:
    return [(s.tower, s.height, s.k) for s in report.suspects]


def rates(seeds: int) -> dict[str, dict[str, str]]:
    out: dict[str, dict[str, str]] = {}
    with tempfile.TemporaryDirectory() as d:
        tmp = Path(d)
        for layout in ("stacked", "flat"):
            key = "sim_pos" if layout == "flat" else "real_pos"
            row: dict[str, str] = {}
            bad_tables = bad_entries = entries = warned = 0
            for seed in range(seeds):
                rng = np.random.default_rng(1000 + seed)
                st = rt.flat_station() if layout == "flat" else rt.stacked_station(rng)
                rep = audit(tmp, clean(st, rng), key)
                bad_tables += rep.failed
                bad_entries += len(flagged(rep))
                warned += len(getattr(rep, "warnings", ()))
                entries += sum(e.status != "missing" for e in rep.entries)
            row["false alarms (tables)"] = f"{bad_tables}/{seeds}"
            row["false alarms (entries)"] = f"{bad_entries}/{entries}"
            row["warnings on clean tables (entries, the table passes)"] = f"{warned}/{entries}"
            for kind in ERRORS[:4] if LEGACY else ERRORS:
                first = named = 0
                for seed in range(seeds):
                    rng = np.random.default_rng(2000 + seed)
                    st = rt.flat_station() if layout == "flat" else rt.stacked_station(rng)
                    q, injected = inject(kind, st, rng)
                    rep = audit(tmp, q, key)
                    got = flagged(rep)
                    first += bool(got) and got[0] in injected
                    said = got + [(w.tower, w.height, w.k) for w in getattr(rep, "warnings", ())]
                    named += bool(said) and said[0] in injected
                row[f"named first: {kind}"] = f"{first}/{seeds}"
                if named != first:
                    row[f"named first, warnings included: {kind}"] = f"{named}/{seeds}"
            out[layout] = row
    return out


def wall(repeats: int = 5) -> float:
    rng = np.random.default_rng(7)
    q = rt.recorded_like(rt.stacked_station(rng), rng).q
    walls = []
    with tempfile.TemporaryDirectory() as d:
        path = rt.write_table(Path(d) / "t.yaml", "real_pos", rt.table_doc(q))
        for _ in range(repeats):
            t0 = time.perf_counter()
            cmd = [str(Path(sys.executable).parent / "ur3hanoi"), "check-table", str(path), "--key", "real_pos",
                   "--fit"]
            subprocess.run(cmd, check=False, capture_output=True)
            walls.append(time.perf_counter() - t0)
    return float(np.median(walls))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--seeds", type=int, default=30)
    ap.add_argument("--legacy", action="store_true", help="the older generator (no heading spread, one approach)")
    ap.add_argument("--no-wall", action="store_true")
    args = ap.parse_args()
    global LEGACY
    LEGACY = args.legacy
    t0 = time.perf_counter()
    result = rates(args.seeds)
    per = (time.perf_counter() - t0) / (2 * args.seeds * (1 + len(ERRORS)))
    print(json.dumps(result, indent=1))
    print(f"audit_table + table generation: {per * 1e3:.0f} ms per table")
    if not args.no_wall:
        print(f"check-table --fit wall time: {wall():.2f} s (median of 5)")
    assert not math.isnan(per)


if __name__ == "__main__":
    main()
