"""Byte-identity of what users get: record the outputs of a commit and compare them with the working tree's.

    python tools/compare_outputs.py [--base REV] [--keep DIR]

For each shipped simulator/real station (``lab_sim``, ``lab_real``, ``ur3e_sim``) it runs, in a scratch folder and
with an empty user cache, ``tables`` (the written file and the printed line), ``plan --csv``, ``solve --json`` and
``check-table --json`` (against the calibration, and ``--fit``) on the shipped course-format table
``tables/lab2_data.yaml`` (``ur3e_sim``: on the table ``tables`` wrote for it), once with the package of ``REV``
(default: the commit before the package was regrouped, checked out into a temporary git worktree) and once with the
working tree's, both under this virtual environment's interpreter, and compares the bytes.

Two fields of ``solve --json`` measure the machine, not the result: ``wall_time_s`` and ``realtime_factor``. They
are masked before the comparison; everything else must be equal to the byte. Exit 0 when every output is equal, 1
otherwise (the differing outputs are named, with their first differing line).
"""

from __future__ import annotations

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BASE_REV = "5fc7b98"
"""main before the package was regrouped (issue 27): the outputs every later layout must reproduce."""

STATIONS = {"lab_sim": "sim_pos", "lab_real": "real_pos", "ur3e_sim": "sim_pos"}
_MACHINE_FIELDS = re.compile(rb'"(wall_time_s|realtime_factor)": [-0-9.e+]+')


def _run(tree: Path, out: Path, name: str, args: list[str], cache: Path) -> None:
    """Run ``ur3hanoi ARGS`` with ``tree``'s package; keep stdout (masked), stderr and the exit code as NAME.*."""
    env = dict(os.environ, PYTHONPATH=str(tree), XDG_CACHE_HOME=str(cache), MUJOCO_GL="egl")
    proc = subprocess.run([sys.executable, "-m", "ur3hanoi", *args], cwd=out, env=env, capture_output=True,
                          timeout=600, check=False)
    (out / f"{name}.stdout").write_bytes(_MACHINE_FIELDS.sub(rb'"\1": MASKED', proc.stdout))
    (out / f"{name}.exit").write_text(f"{proc.returncode}\n")


def record(tree: Path, out: Path) -> None:
    """Every output of the package in ``tree`` into the folder ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    cache = out / ".cache"
    course = ROOT / "tables" / "lab2_data.yaml"
    for station, key in STATIONS.items():
        table = f"{station}_tables.yaml"
        _run(tree, out, f"{station}_tables", ["tables", station, "--key", key, "-o", table], cache)
        _run(tree, out, f"{station}_plan", ["plan", "--calibration", station, "--start", "1", "--end", "3",
                                            "--csv", f"{station}_plan.csv"], cache)
        _run(tree, out, f"{station}_solve", ["solve", "--calibration", station, "--start", "1", "--end", "3",
                                             "--json"], cache)
        source = table if station == "ur3e_sim" else str(course)
        _run(tree, out, f"{station}_check", ["check-table", source, "--key", key, "--calibration", station,
                                             "--json"], cache)
        _run(tree, out, f"{station}_fit", ["check-table", source, "--key", key, "--fit", "--base", station,
                                           "--json"], cache)
    shutil.rmtree(cache, ignore_errors=True)


def compare(old: Path, new: Path) -> list[str]:
    """The differences between two recordings (empty when every file is equal to the byte)."""
    names = sorted({p.name for p in old.iterdir()} | {p.name for p in new.iterdir()})
    diffs = []
    for name in names:
        a, b = old / name, new / name
        if not a.exists() or not b.exists():
            diffs.append(f"{name}: only in {'new' if b.exists() else 'old'}")
            continue
        x, y = a.read_bytes(), b.read_bytes()
        if x != y:
            line = next((i for i, (p, q) in enumerate(zip(x.splitlines(), y.splitlines(), strict=False)) if p != q),
                        min(len(x.splitlines()), len(y.splitlines())))
            diffs.append(f"{name}: differs from line {line + 1}")
    return diffs


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--base", default=BASE_REV, help=f"the commit to compare with (default {BASE_REV})")
    parser.add_argument("--keep", type=Path, help="keep both recordings in this folder (old/, new/)")
    args = parser.parse_args()
    scratch = Path(tempfile.mkdtemp(prefix="ur3hanoi-compare-"))
    base_tree = scratch / "base"
    try:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(base_tree), args.base],
                       check=True)
        top = args.keep if args.keep is not None else scratch
        record(base_tree, top / "old")
        record(ROOT, top / "new")
        diffs = compare(top / "old", top / "new")
        n = len(list((top / "new").iterdir()))
        for line in diffs:
            print(f"DIFFERENT {line}")
        print(f"{n - len(diffs)} of {n} outputs byte-identical to {args.base} "
              f"({', '.join(STATIONS)}: tables, plan --csv, solve --json, check-table --json)")
        return 1 if diffs else 0
    finally:
        subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(base_tree)], check=False)
        shutil.rmtree(scratch, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
