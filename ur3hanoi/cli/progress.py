"""Progress of ``ur3hanoi solve`` on stderr: a bar on a terminal; plain lines every :data:`PROGRESS_STEP` of the
run when stderr is not a terminal and the run renders, or with ``--progress``."""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from ur3hanoi.sim import ProgressFn

PROGRESS_STEP = 0.1
"""Fraction of the run between two plain progress lines (when stderr is not a terminal)."""

SIM_SHARE = 0.05
"""Share of the progress bar given to simulating when the frames render afterwards in worker processes (the
simulation takes about 1.5 s of a 30 s video job); the rest counts the frames rendered."""


def progress_bar(fraction: float, label: str) -> None:
    width = 30
    filled = round(width * fraction)
    end = "\n" if fraction >= 1.0 else ""
    print(f"\r[{'#' * filled}{'.' * (width - filled)}] {100 * fraction:5.1f}% {label:<12}", end=end,
          file=sys.stderr, flush=True)


class ProgressLines:
    """Progress as plain stderr lines every :data:`PROGRESS_STEP` of the run (for logs and pipes), with the
    number of frames written so far when rendering."""

    def __init__(self, recorder: object | None) -> None:
        self.recorder = recorder
        self.reported = -1

    def __call__(self, fraction: float, label: str) -> None:
        step = math.floor(fraction / PROGRESS_STEP + 1e-9)
        if step <= self.reported:
            return
        self.reported = step
        frames = getattr(self.recorder, "count", None)
        extra = f", {frames} frames" if frames is not None else ""
        print(f"ur3hanoi solve: {100 * fraction:3.0f} % ({label}{extra})", file=sys.stderr, flush=True)


def phases(progress: ProgressFn | None) -> tuple[ProgressFn | None, ProgressFn | None]:
    """One progress bar over two phases: the simulation (:data:`SIM_SHARE`), then the frames rendered."""
    if progress is None:
        return None, None

    def simulating(fraction: float, label: str) -> None:
        progress(SIM_SHARE * fraction, "simulated" if fraction >= 1.0 else label)

    def rendering(fraction: float, label: str) -> None:
        progress(SIM_SHARE + (1.0 - SIM_SHARE) * fraction, label)

    return simulating, rendering


def progress_sink(args: argparse.Namespace, recorder: object | None) -> ProgressFn | None:
    """A bar on a terminal; plain lines when rendering or with --progress; nothing otherwise (and never with
    --view, whose window shows the run)."""
    if args.view:
        return None
    if sys.stderr.isatty():
        return progress_bar
    if args.progress or args.video or args.frames:
        return ProgressLines(recorder)
    return None
