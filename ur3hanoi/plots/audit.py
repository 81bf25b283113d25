"""The audit of a lab table as a picture (``check-table --plot``): a top view and a side view of the recorded
suction points (FK of every entry present) against the reference grid (the towers fitted to the table, or the
calibration's), suspect entries marked in red and labelled with their tower/height/pose and measured error.

It takes the audit's own report (:class:`ur3hanoi.audit.AuditReport`: statuses and errors) with the table and the
reference grid; towers and heights are labelled from 1.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.audit import AuditReport
from ur3hanoi.grid import ABOVE, ON, T_world_tcp
from ur3hanoi.labfile import RecordedTable
from ur3hanoi.plots.figure import require_matplotlib, save_figure
from ur3hanoi.station import Station

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

SUSPECT_COLOUR = "#d62728"
"""Marker colour of a suspect entry (matplotlib's tab:red)."""
OK_COLOUR = "#1f77b4"
"""Marker colour of an entry within the thresholds (tab:blue)."""
GRID_COLOUR = "#7f7f7f"
"""The reference grid (tab:grey)."""


def fitted_reference(table: RecordedTable, base: Station, tol_mm: float | None = None,
                     tol_deg: float | None = None) -> Station:
    """The grid :func:`ur3hanoi.audit.audit_table` fits to ``table`` (same fit, same seed: the same grid)."""
    from ur3hanoi.audit.fitted import _grid_like
    from ur3hanoi.calibrate import fit_station
    from ur3hanoi.taught import taught_from_recorded

    grid = _grid_like(base, table.n_towers, table.n_heights)
    return fit_station(grid, taught_from_recorded(table), tol_mm=tol_mm, tol_deg=tol_deg).station


def _points(report: AuditReport, table: RecordedTable, grid: Station
            ) -> tuple[list[tuple[int, int, int]], FloatArray, FloatArray, list[str], list[float]]:
    """Present entries (slot, recorded point, grid point [m, world], status, error [mm])."""
    from ur3hanoi.calibrate.grid_fit import measure

    by_slot = {(e.tower, e.height, e.k): e for e in report.entries}
    slots = [s for s in by_slot if by_slot[s].status != "missing" and bool(table.present[s])]
    measured = measure(grid, [table.q[s] for s in slots]).p_world if slots else np.zeros((0, 3))
    ref = np.array([T_world_tcp(grid, *s).translation for s in slots]).reshape(-1, 3)
    return (slots, measured, ref, [by_slot[s].status for s in slots], [by_slot[s].error_mm for s in slots])


def _side_axis(grid: Station) -> FloatArray:
    """The horizontal direction of the side view: the grid's main direction in x-y (its towers' row)."""
    pts = np.array([T_world_tcp(grid, t, h, ON).translation[:2]
                    for t in range(grid.n_towers) for h in range(grid.n_heights)])
    centred = pts - pts.mean(axis=0)
    if len(pts) < 2 or np.allclose(centred, 0.0):
        return np.array([1.0, 0.0])
    axis = np.linalg.svd(centred)[2][0]
    return axis if axis[np.argmax(np.abs(axis))] > 0 else -axis


def audit_figure(report: AuditReport, table: RecordedTable, grid: Station, title: str = "") -> Figure:
    """Top view (x-y) and side view (along the towers' row, z) in mm."""
    require_matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    slots, measured, ref, status, err = _points(report, table, grid)
    axis = _side_axis(grid)
    fig = Figure(figsize=(12, 5.6))
    top, side = fig.subplots(1, 2)
    views: list[tuple[Axes, str, str]] = [(top, "top view", "y [mm]"), (side, "side view", "z [mm]")]

    def xy(p: FloatArray, view: Axes) -> tuple[FloatArray, FloatArray]:
        p = np.atleast_2d(p) * 1e3
        if view is top:
            return p[:, 0], p[:, 1]
        return p[:, :2] @ axis, p[:, 2]

    for ax, name, ylabel in views:
        # The reference grid: contact points (squares) and above points (triangles), joined per tower.
        for t in range(grid.n_towers):
            on = np.array([T_world_tcp(grid, t, h, ON).translation for h in range(grid.n_heights)])
            above = np.array([T_world_tcp(grid, t, h, ABOVE).translation for h in range(grid.n_heights)])
            ax.plot(*xy(on, ax), "-", color=GRID_COLOUR, lw=0.8, alpha=0.6, zorder=1)
            ax.plot(*xy(on, ax), "s", mfc="none", mec=GRID_COLOUR, ms=9, zorder=2)
            ax.plot(*xy(above, ax), "^", mfc="none", mec=GRID_COLOUR, ms=8, zorder=2)
            lx, ly = xy(on[0], ax)
            ax.annotate(f"tower {t + 1}", (float(lx[0]), float(ly[0])), textcoords="offset points", xytext=(0, -16),
                        ha="center", fontsize=9, color="#444444")
        ok = [i for i, s in enumerate(status) if s != "suspect"]
        bad = [i for i, s in enumerate(status) if s == "suspect"]
        if ok:
            ax.plot(*xy(measured[ok], ax), "o", color=OK_COLOUR, ms=4, zorder=3)
        for i in bad:
            # Recorded point, joined to where the grid puts its slot.
            seg = np.vstack([ref[i], measured[i]])
            ax.plot(*xy(seg, ax), "-", color=SUSPECT_COLOUR, lw=1.2, zorder=3)
            px, py = xy(measured[i], ax)
            ax.plot(px, py, "X", color=SUSPECT_COLOUR, ms=11, mec="white", mew=0.8, zorder=4)
            t, h, k = slots[i]
            ax.annotate(f"tower {t + 1} height {h + 1} {'on' if k == ON else 'above'}\n{err[i]:.1f} mm",
                        (float(px[0]), float(py[0])), textcoords="offset points", xytext=(8, 6), fontsize=9,
                        color=SUSPECT_COLOUR, fontweight="bold", zorder=5)
        ax.set_title(name)
        ax.set_xlabel("x [mm]" if ax is top else "along the towers [mm]")
        ax.set_ylabel(ylabel)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, lw=0.3, alpha=0.5)
    handles = [Line2D([], [], ls="none", marker="s", mfc="none", mec=GRID_COLOUR, label="reference: on"),
               Line2D([], [], ls="none", marker="^", mfc="none", mec=GRID_COLOUR, label="reference: above"),
               Line2D([], [], ls="none", marker="o", color=OK_COLOUR, label="recorded: ok"),
               Line2D([], [], ls="none", marker="X", color=SUSPECT_COLOUR, label="recorded: suspect")]
    missing = len(report.missing)
    fig.legend(handles=handles, loc="lower center", ncol=4, frameon=False)
    th = report.thresholds
    fig.suptitle((title + "\n" if title else "") +
                 f"{len(slots)} entries, {len(report.suspects)} suspect (over {th.mm:.1f} mm / {th.deg:.1f} deg), "
                 f"{missing} missing; rms {report.rms_mm:.2f} mm", fontsize=11)
    fig.subplots_adjust(bottom=0.16)
    return fig


def write_audit_plot(path: str | Path, report: AuditReport, table: RecordedTable, grid: Station, title: str = "",
                     inputs: tuple[Path, ...] = ()) -> Path:
    """Draw :func:`audit_figure` into ``path`` (PNG, SVG or PDF by extension), atomically."""
    return save_figure(audit_figure(report, table, grid, title), path, inputs)
