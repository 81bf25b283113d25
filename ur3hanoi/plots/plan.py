"""A plan's joint motion as a picture (``plan --plot``): the six joint positions [deg] and speeds [deg/s] against
time, with the joints' position and speed limits (dashed, at the plan's ``--speed``), and the plan's phases
shaded (approach, grasp, carry, place, ...). Joints are numbered 1-6 as on the pendant."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ur3hanoi.plan.types import Phase, Plan
from ur3hanoi.plots.figure import require_matplotlib, save_figure

if TYPE_CHECKING:
    from matplotlib.figure import Figure

JOINT_NAMES = ("1 base", "2 shoulder", "3 elbow", "4 wrist 1", "5 wrist 2", "6 wrist 3")
JOINT_COLOURS = ("#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2")
PHASE_COLOURS: dict[Phase, str] = {
    Phase.TRANSIT: "#ffffff",
    Phase.DESCEND_PICK: "#c6dbef",
    Phase.GRASP_DWELL: "#6baed6",
    Phase.LIFT: "#fdd0a2",
    Phase.CARRY: "#fdae6b",
    Phase.DESCEND_PLACE: "#fd8d3c",
    Phase.RELEASE_DWELL: "#a1d99b",
    Phase.RETREAT: "#e5f5e0",
    Phase.HOME: "#d9d9d9",
}
"""Background of each phase: blues while picking, oranges while carrying, greens while placing."""
LIMIT_COLOUR = "#d62728"


def _runs(values: np.ndarray) -> list[tuple[int, int, int]]:
    """(value, first index, last index) of each run of equal values."""
    edges = np.flatnonzero(np.diff(values)) + 1
    starts = np.concatenate([[0], edges])
    ends = np.concatenate([edges - 1, [len(values) - 1]])
    return [(int(values[a]), int(a), int(b)) for a, b in zip(starts, ends, strict=True)]


def plan_figure(plan: Plan, title: str = "") -> Figure:
    """Positions and speeds against time, limits dashed, phases shaded, move numbers on top."""
    require_matplotlib()
    from matplotlib.figure import Figure
    from matplotlib.patches import Patch

    tr = plan.trajectory
    lim = plan.station.limits
    v_max = np.degrees(np.asarray(plan.limits.v_max)) if plan.limits is not None else \
        np.degrees(np.asarray(lim.v_max)) * plan.config.speed
    fig = Figure(figsize=(12, 7))
    ax_q, ax_v = fig.subplots(2, 1, sharex=True)
    t = tr.t
    for ax in (ax_q, ax_v):
        for phase, a, b in _runs(tr.phase):
            colour = PHASE_COLOURS.get(Phase(phase), "#ffffff")
            if colour != "#ffffff":
                ax.axvspan(t[a], t[min(b + 1, len(t) - 1)], color=colour, lw=0, zorder=0)
    q_deg, v_deg = np.degrees(tr.q), np.degrees(tr.qd)
    for j in range(6):
        ax_q.plot(t, q_deg[:, j], color=JOINT_COLOURS[j], lw=1.3, label=f"joint {JOINT_NAMES[j]}", zorder=3)
        ax_v.plot(t, v_deg[:, j], color=JOINT_COLOURS[j], lw=1.1, zorder=3)
    # Speed limits: one dashed pair per distinct value (180 deg/s joints 1-3, 360 deg/s wrists, at full speed).
    for value in sorted(set(np.round(v_max, 6))):
        joints = [j + 1 for j in range(6) if math.isclose(v_max[j], value, rel_tol=1e-6)]
        label = f"speed limit joints {joints[0]}-{joints[-1]}" if len(joints) > 1 else f"speed limit joint {joints[0]}"
        for sign in (1, -1):
            ax_v.axhline(sign * value, color=LIMIT_COLOUR, ls="--", lw=1.0, zorder=2)
        ax_v.annotate(f"{label}: {value:g} deg/s", (t[0], value), textcoords="offset points", xytext=(4, -11),
                      fontsize=8, color=LIMIT_COLOUR)
    # Position limits, when the motion comes within 30 deg of one (the UR3's +-360 deg would flatten the curves).
    q_min, q_max = np.degrees(np.asarray(lim.q_min)), np.degrees(np.asarray(lim.q_max))
    for j in range(6):
        for bound in (q_min[j], q_max[j]):
            if np.min(np.abs(q_deg[:, j] - bound)) < 30.0:
                ax_q.axhline(bound, color=JOINT_COLOURS[j], ls="--", lw=1.0)
                ax_q.annotate(f"joint {j + 1} limit {bound:g} deg", (t[0], bound), textcoords="offset points",
                              xytext=(4, 3), fontsize=8, color=JOINT_COLOURS[j])
    # Move numbers over the top axis.
    for mv, a, b in _runs(tr.move_index):
        if mv >= 0:
            ax_q.annotate(f"move {mv + 1}", (0.5 * (t[a] + t[b]), 1.0), xycoords=("data", "axes fraction"),
                          xytext=(0, 3), textcoords="offset points", ha="center", va="bottom", fontsize=8)
    ax_q.set_ylabel("joint position [deg]")
    ax_v.set_ylabel("joint speed [deg/s]")
    ax_v.set_xlabel("time [s]")
    ax_v.set_xlim(t[0], t[-1])
    ax_q.legend(loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8, frameon=False)
    phases = [Patch(color=c, label=p.name.lower().replace("_", " ")) for p, c in PHASE_COLOURS.items()
              if c != "#ffffff" and np.any(tr.phase == p)]
    phases.insert(0, Patch(facecolor="#ffffff", edgecolor="#bbbbbb", label="transit"))
    ax_v.legend(handles=phases, loc="upper left", bbox_to_anchor=(1.005, 1.0), fontsize=8, frameon=False,
                title="phase", title_fontsize=8)
    for ax in (ax_q, ax_v):
        ax.grid(True, lw=0.3, alpha=0.5, zorder=1)
    peak = np.max(np.abs(v_deg) / v_max)
    fig.suptitle((title + "\n" if title else "") +
                 f"cycle {plan.duration_s:.2f} s, {len(plan.moves)} moves; peak speed {100 * peak:.0f} % of the "
                 "limit", fontsize=11)
    fig.subplots_adjust(hspace=0.12, right=0.82)
    return fig


def write_plan_plot(path: str | Path, plan: Plan, title: str = "", inputs: tuple[Path, ...] = ()) -> Path:
    """Draw :func:`plan_figure` into ``path`` (PNG, SVG or PDF by extension), atomically."""
    return save_figure(plan_figure(plan, title), path, inputs)
