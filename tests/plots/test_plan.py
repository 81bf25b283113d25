"""ur3hanoi.plots.plan and ``plan --plot``: one shaded carry band per move, the speed limits drawn, from the
pixels of the PNG."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from tests.support.sim_helpers import planned
from ur3hanoi.cli import main
from ur3hanoi.plan.types import Phase
from ur3hanoi.plots.plan import LIMIT_COLOUR, PHASE_COLOURS, write_plan_plot


def _pixels(png: Path, colour: str, tol: int = 6) -> np.ndarray:
    img = np.asarray(Image.open(png).convert("RGB")).astype(int)
    ref = np.array([int(colour[i:i + 2], 16) for i in (1, 3, 5)])
    return np.abs(img - ref).max(axis=-1) <= tol


def _bands(row: np.ndarray, min_width: int = 3, max_gap: int = 4) -> int:
    """Runs of True along a row (gaps up to ``max_gap`` px, where a curve crosses, are bridged)."""
    idx = np.flatnonzero(row)
    if idx.size == 0:
        return 0
    runs, start, last = [], idx[0], idx[0]
    for i in idx[1:]:
        if i - last > max_gap + 1:
            runs.append((start, last))
            start = i
        last = i
    runs.append((start, last))
    return sum(1 for a, b in runs if b - a + 1 >= min_width)


def test_one_carry_band_per_move_and_the_speed_limits(tmp_path: Path) -> None:
    plan = planned("lab_sim", 0, 2)
    out = write_plan_plot(tmp_path / "plan.png", plan)
    carry = _pixels(out, PHASE_COLOURS[Phase.CARRY])
    # Columns through a band are carry-coloured over both axes' height (the legend's swatch is a few px high).
    tall = carry.sum(axis=0) > 0.25 * carry.shape[0]
    assert _bands(tall) == len(plan.moves) == 7
    img = np.asarray(Image.open(out).convert("RGB")).astype(int)
    assert LIMIT_COLOUR == "#d62728"
    # Four dashed red lines (+-180, +-360 deg/s) span the plot: rows (a line is antialiased over two) with many
    # red pixels (the joints' colours have no red; the phases' oranges have green over 140).
    limit = (img[..., 0] > 150) & (img[..., 1] < 110) & (img[..., 2] < 110)
    limit = limit[:-1] | limit[1:]
    long_rows = np.flatnonzero(limit.sum(axis=1) > 0.3 * limit.shape[1])
    groups = np.split(long_rows, np.flatnonzero(np.diff(long_rows) > 2) + 1)
    assert len(groups) == 4


def test_cli_plan_plot(tmp_path: Path) -> None:
    out = tmp_path / "plan.svg"
    assert main(["plan", "--start", "1", "--end", "2", "--blocks", "2", "--no-collision", "--plot", str(out)]) == 0
    text = out.read_text()
    assert text.startswith("<?xml") and "<!-- move 3 -->" in text and "<!-- move 4 -->" not in text
