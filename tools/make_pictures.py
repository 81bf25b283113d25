"""Regenerate the pictures of the documentation from real runs of the ``ur3hanoi`` command (``make pictures``).

- ``docs/examples/hand_recorded.yaml``: a hand-recorded-like ``real_pos`` table of ``lab_real`` (the generated
  table with seeded 0.15 deg jitter per joint, rounded as read off a pendant, and one 10 deg shoulder typo);
- ``docs/audit.png``: ``check-table --fit --plot`` of that table;
- ``docs/plan.png``: ``plan --plot`` of a 3-block solve on ``lab_sim``;
- ``docs/replay.png``: the replay page of a solve whose block falls in move 4, opened in Debian's headless
  chromium with the network off (``unshare -n``), half a second after the halt.

Every picture comes from the commands a student runs, so a change in the code shows in the pictures the next time
this runs. Usage: ``.venv/bin/python tools/make_pictures.py [--only audit|plan|replay]``.
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import yaml

REPO = Path(__file__).resolve().parents[1]
DOCS = REPO / "docs"
EXAMPLE = DOCS / "examples" / "hand_recorded.yaml"
TYPO = (1, 2, 0)  # tower 2, height 3, on (0-based list indices of the lab file)
SHOULDER, TYPO_DEG, JITTER_DEG, SEED = 1, 10.0, 0.15, 29
REPLAY_SIZE = (900, 560)
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
                  "--enable-unsafe-swiftshader", "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync", "--hide-scrollbars"]


def ur3hanoi(*args: str, ok: tuple[int, ...] = (0,), cwd: Path = REPO) -> subprocess.CompletedProcess[str]:
    """Run ``ur3hanoi ARGS`` in ``cwd`` with this interpreter; fail unless it exits with one of ``ok``."""
    proc = subprocess.run([sys.executable, "-m", "ur3hanoi", *args], capture_output=True, text=True, cwd=cwd)
    if proc.returncode not in ok:
        sys.exit(f"make_pictures: ur3hanoi {' '.join(args)} exited {proc.returncode}:\n{proc.stderr}")
    return proc


def hand_recorded_table(tmp: Path) -> str:
    """The generated lab_real table as a person would record it: jitter, pendant rounding, one shoulder typo (the
    text of ``docs/examples/hand_recorded.yaml``)."""
    generated = tmp / "generated.yaml"
    ur3hanoi("tables", "lab_real", "--key", "real_pos", "-o", str(generated))
    q = np.array(yaml.safe_load(generated.read_text())["real_pos"], dtype=float)
    rng = np.random.default_rng(SEED)
    q += np.radians(rng.normal(0.0, JITTER_DEG, size=q.shape))
    q[TYPO][SHOULDER] += math.radians(TYPO_DEG)
    rows = []
    for t, tower in enumerate(q):
        for h, slot in enumerate(tower):
            for k, pose in enumerate(slot):
                lead = "- - - " if h == 0 and k == 0 else "  - - " if k == 0 else "    - "
                values = ", ".join(f"{v:.4f}" for v in pose)
                name = "on" if k == 0 else "above"
                rows.append(f"{lead}[{values}]  # tower {t + 1} height {h + 1} {name}")
    head = ("# A hand-recorded real_pos table of the example station lab_real, as students record it (made by\n"
            "# tools/make_pictures.py: the generated table with 0.15 deg of jitter per joint and one typo).\n")
    return head + "real_pos:\n" + "\n".join(rows) + "\n"


def audit_picture() -> None:
    # Run beside the table, as the audit page shows it: the picture's title names the file as the student typed it.
    ur3hanoi("check-table", EXAMPLE.name, "--key", "real_pos", "--fit", "--plot", str(DOCS / "audit.png"), ok=(1,),
             cwd=EXAMPLE.parent)


def plan_picture() -> None:
    ur3hanoi("plan", "--start", "1", "--end", "3", "--plot", str(DOCS / "plan.png"))


def offline_prefix() -> list[str]:
    """A prefix that runs a program in a new network namespace (no network at all)."""
    for prefix in (["unshare", "-n"], ["unshare", "-rn"]):
        if shutil.which(prefix[0]) and subprocess.run([*prefix, "true"], capture_output=True).returncode == 0:
            return prefix
    sys.exit("make_pictures: cannot make a network namespace (unshare -n) to open the page offline")


def screenshot(url: str, out: Path, size: tuple[int, int], profile: Path) -> None:
    """A PNG of ``url`` in headless chromium, network off, with a fresh profile."""
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    if exe is None:
        sys.exit("make_pictures: Debian's chromium is not installed (tools/ensure-system-deps.sh installs it)")
    args = [*offline_prefix(), exe, *CHROMIUM_FLAGS, f"--user-data-dir={profile}",
            f"--window-size={size[0]},{size[1]}", f"--screenshot={out}", url]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=180)
    if proc.returncode != 0 or not out.exists():
        sys.exit(f"make_pictures: chromium failed on {url}:\n{proc.stderr[-2000:]}")


def replay_picture(tmp: Path) -> None:
    page = tmp / "replay.html"
    run = ur3hanoi("solve", "--start", "1", "--end", "3", "--drop-during-move", "4", "--html", str(page), "--json",
                   ok=(3,))
    halted = min(e["t"] for e in json.loads(run.stdout)["feedback_events"] if e["kind"] == "dropped")
    screenshot(f"{page.as_uri()}#t={halted + 0.5:.1f}", DOCS / "replay.png", REPLAY_SIZE, tmp / "profile")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--only", choices=["audit", "plan", "replay"], help="make one picture only")
    only = parser.parse_args().only
    with tempfile.TemporaryDirectory(prefix="ur3hanoi-pictures-") as name:
        tmp = Path(name)
        if only in (None, "audit"):
            EXAMPLE.parent.mkdir(exist_ok=True)
            EXAMPLE.write_text(hand_recorded_table(tmp))
            audit_picture()
        if only in (None, "plan"):
            plan_picture()
        if only in (None, "replay"):
            replay_picture(tmp)
    return 0


if __name__ == "__main__":
    sys.exit(main())
