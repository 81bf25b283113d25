"""The audit of a lab table as a picture (``check-table --plot``): a top view and a side view of what the audit
measured, drawn from its report alone (:class:`ur3hanoi.audit.AuditReport`), with no fit of its own.

Each entry present is drawn at its measured suction point (:attr:`~ur3hanoi.audit.AuditEntry.point_m`); the
reference is where the audit puts it (:attr:`~ur3hanoi.audit.AuditEntry.fitted_m`): the contacts' reference points
joined per tower (squares), the above poses' (the nearest accepted point) as triangles. Entries within the rule are
blue dots, warned entries orange dots and flagged (suspect) entries red crosses joined to their reference point and
labelled with their tower/height/pose and measured error. Towers and heights are labelled from 1. The same picture
serves both audits: against the grid fitted to the table (``--fit``) and against a calibration.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.audit import AuditEntry, AuditReport
from ur3hanoi.plots.figure import require_matplotlib, save_figure
from ur3hanoi.station.grid import ABOVE, ON

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure

SUSPECT_COLOUR = "#d62728"
"""Marker colour of a flagged (suspect) entry (matplotlib's tab:red)."""
WARN_COLOUR = "#ff7f0e"
"""Marker colour of a warned entry (tab:orange)."""
OK_COLOUR = "#1f77b4"
"""Marker colour of an entry within the rule (tab:blue); hollow for an unchecked one."""
GRID_COLOUR = "#7f7f7f"
"""The reference towers (tab:grey)."""
REFERENCE_GID = "reference tower {}"
"""The ``gid`` of the line through a tower's contact reference points (tower from 1), in both views."""


@dataclass(frozen=True, eq=False)
class AuditPicture:
    """What :func:`audit_figure` draws, taken from the report as it is [m, world].

    Attributes:
        entries: the entries drawn: present, with a measured point, in the report's order.
        towers: ``(tower, points)`` per tower with a contact reference (0-based, ascending): its contacts'
            ``fitted_m`` by height, shape ``(n, 3)`` [m].
        side_axis: the horizontal unit direction (x, y) of the side view: the towers' row.
    """

    entries: tuple[AuditEntry, ...]
    towers: tuple[tuple[int, FloatArray], ...]
    side_axis: FloatArray = field(repr=False)


def _finite(v: tuple[float, float, float]) -> bool:
    return not any(math.isnan(x) for x in v)


def audit_picture(report: AuditReport) -> AuditPicture:
    """The points :func:`audit_figure` draws for ``report`` (no fit: the report's ``point_m`` and ``fitted_m``)."""
    entries = tuple(e for e in report.entries if e.status != "missing" and _finite(e.point_m))
    contacts = sorted((e for e in report.entries if e.k == ON and _finite(e.fitted_m)),
                      key=lambda e: (e.tower, e.height))
    towers = tuple((t, np.array([e.fitted_m for e in contacts if e.tower == t], dtype=float))
                   for t in sorted({e.tower for e in contacts}))
    refs = [e.fitted_m for e in contacts] or [e.point_m for e in entries]
    return AuditPicture(entries=entries, towers=towers, side_axis=_side_axis(np.array(refs, dtype=float)))


def _side_axis(points: FloatArray) -> FloatArray:
    """The main direction of ``points`` in x-y (the towers' row), pointing to +x or +y."""
    xy = points.reshape(-1, 3)[:, :2]
    centred = xy - xy.mean(axis=0) if len(xy) else xy
    if len(xy) < 2 or np.allclose(centred, 0.0):
        return np.array([1.0, 0.0])
    axis: FloatArray = np.linalg.svd(centred)[2][0]
    return axis if axis[np.argmax(np.abs(axis))] > 0 else -axis


def _rule_line(report: AuditReport) -> str:
    """The thresholds the entries were judged by, in mm and deg."""
    rule = report.rule
    if rule is not None:
        return (f"flagged over {rule.flag_mm:g} mm / {rule.flag_deg:g} deg (contacts; above poses by clearance and "
                f"line), warned over {rule.warn_mm:.1f} mm / {rule.warn_deg:.1f} deg")
    th = report.thresholds
    return f"flagged over {th.mm:g} mm / {th.deg:g} deg"


def _error_text(report: AuditReport, e: AuditEntry) -> str:
    """The measured error of a flagged entry [mm], and its angle when that is what is over the rule [deg]."""
    deg = report.rule.flag_deg if report.rule is not None else report.thresholds.deg
    angle = e.tilt_deg if report.rule is not None else e.rot_deg
    return f"{e.error_mm:.1f} mm" + (f", {angle:.1f} deg" if angle > deg else "")


def audit_figure(report: AuditReport, title: str = "") -> Figure:
    """Top view (x-y) and side view (along the towers' row, z) in mm of :func:`audit_picture`."""
    require_matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    pic = audit_picture(report)
    axis = pic.side_axis
    fig = Figure(figsize=(12, 5.8))
    top, side = fig.subplots(1, 2)
    views: list[tuple[Axes, str, str]] = [(top, "top view", "y [mm]"), (side, "side view", "z [mm]")]

    def xy(p: FloatArray | tuple[float, ...], view: Axes) -> tuple[FloatArray, FloatArray]:
        pts = np.atleast_2d(np.asarray(p, dtype=float)) * 1e3
        if view is top:
            return pts[:, 0], pts[:, 1]
        return pts[:, :2] @ axis, pts[:, 2]

    by_status = {s: [e for e in pic.entries if e.status == s] for s in ("ok", "warn", "suspect", "unchecked")}
    above_refs = [e.fitted_m for e in pic.entries if e.k == ABOVE and _finite(e.fitted_m)]
    for ax, name, ylabel in views:
        for t, pts in pic.towers:
            ax.plot(*xy(pts, ax), "-s", color=GRID_COLOUR, lw=0.8, mfc="none", mec=GRID_COLOUR, ms=9, zorder=1,
                    gid=REFERENCE_GID.format(t + 1))
            lx, ly = xy(pts[0], ax)
            ax.annotate(f"tower {t + 1}", (float(lx[0]), float(ly[0])), textcoords="offset points", xytext=(0, -16),
                        ha="center", fontsize=9, color="#444444")
        if above_refs:
            ax.plot(*xy(np.array(above_refs), ax), "^", mfc="none", mec=GRID_COLOUR, ms=8, zorder=2)
        if by_status["ok"]:
            ax.plot(*xy(np.array([e.point_m for e in by_status["ok"]]), ax), "o", color=OK_COLOUR, ms=4, zorder=3)
        if by_status["unchecked"]:
            ax.plot(*xy(np.array([e.point_m for e in by_status["unchecked"]]), ax), "o", mfc="none", mec=OK_COLOUR,
                    ms=6, zorder=3)
        for e in by_status["warn"]:
            if _finite(e.fitted_m):
                ax.plot(*xy(np.array([e.fitted_m, e.point_m]), ax), "-", color=WARN_COLOUR, lw=1.0, zorder=3)
            ax.plot(*xy(e.point_m, ax), "o", color=WARN_COLOUR, ms=6, zorder=4)
        for e in by_status["suspect"]:
            # The measured point, joined to where the audit puts this slot.
            if _finite(e.fitted_m):
                ax.plot(*xy(np.array([e.fitted_m, e.point_m]), ax), "-", color=SUSPECT_COLOUR, lw=1.2, zorder=3)
            px, py = xy(e.point_m, ax)
            ax.plot(px, py, "X", color=SUSPECT_COLOUR, ms=11, mec="white", mew=0.8, zorder=4)
            ax.annotate(f"{e.label}\n{_error_text(report, e)}", (float(px[0]), float(py[0])),
                        textcoords="offset points", xytext=(8, 6), fontsize=9, color=SUSPECT_COLOUR,
                        fontweight="bold", zorder=5)
        ax.set_title(name)
        ax.set_xlabel("x [mm]" if ax is top else "along the towers [mm]")
        ax.set_ylabel(ylabel)
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(True, lw=0.3, alpha=0.5)
    plain = "fitted grid" if report.fitted else "calibration"
    on_ref, above_ref = ("fit of the other contacts", "nearest accepted") if report.rule is not None else (plain, plain)
    handles = [Line2D([], [], ls="-", marker="s", lw=0.8, color=GRID_COLOUR, mfc="none", mec=GRID_COLOUR,
                      label=f"reference: on ({on_ref})"),
               Line2D([], [], ls="none", marker="^", mfc="none", mec=GRID_COLOUR,
                      label=f"reference: above ({above_ref})")]
    shown = [("ok", Line2D([], [], ls="none", marker="o", color=OK_COLOUR, label="recorded: ok")),
             ("unchecked", Line2D([], [], ls="none", marker="o", mfc="none", mec=OK_COLOUR,
                                  label="recorded: unchecked")),
             ("warn", Line2D([], [], ls="none", marker="o", color=WARN_COLOUR, label="recorded: warned")),
             ("suspect", Line2D([], [], ls="none", marker="X", color=SUSPECT_COLOUR, label="recorded: flagged"))]
    handles += [h for status, h in shown if by_status[status]]  # only what the picture holds
    fig.legend(handles=handles, loc="lower center", ncol=len(handles), frameon=False)
    counts = ", ".join(f"{len(by_status[s])} {word}" for s, word in
                       (("ok", "ok"), ("warn", "warned"), ("suspect", "flagged"), ("unchecked", "unchecked"))
                       if by_status[s] or s in ("ok", "suspect"))
    summary = (f"{len(pic.entries)} entries: {counts}, {len(report.missing)} missing; rms {report.rms_mm:.2f} mm "
               f"over {report.points_used} {'contacts' if report.rule is not None else 'entries'}")
    head = textwrap.fill(title, 140) + "\n" if title else ""
    fig.suptitle(f"{head}{summary}\n{_rule_line(report)}", fontsize=11)
    fig.subplots_adjust(bottom=0.16, top=0.8 if title else 0.85)
    return fig


def write_audit_plot(path: str | Path, report: AuditReport, title: str = "", inputs: tuple[Path, ...] = ()) -> Path:
    """Draw :func:`audit_figure` into ``path`` (PNG, SVG or PDF by extension), atomically."""
    return save_figure(audit_figure(report, title), path, inputs)


__all__ = ["AuditPicture", "audit_figure", "audit_picture", "write_audit_plot"]
