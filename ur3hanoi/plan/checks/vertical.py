"""The vertical line: in every approach and retreat, the suction point within the tolerance of the block's line, and,
placing onto a stack, within the placing band's tighter tolerance just above contact
(:func:`ur3hanoi.plan.motion.vertical.place_band`).

Returns human-readable violations (empty: the check passed); :func:`ur3hanoi.plan.plan_moves` collects them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ur3hanoi.hanoi import Move
from ur3hanoi.plan.kinematics import tcp_positions_world
from ur3hanoi.plan.motion.vertical import place_band
from ur3hanoi.plan.types import VERTICAL_PHASES, Phase, Trajectory
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import contact_point_world


def check_vertical(tr: Trajectory, moves: Sequence[Move], station: Station, tol_m: float) -> tuple[list[str], float]:
    """FK at every sample of the vertical phases: suction point within ``tol_m`` of the block's vertical line.

    Returns (violations, worst deviation [m]).
    """
    out: list[str] = []
    vert = np.flatnonzero(np.isin(tr.phase, [int(p) for p in VERTICAL_PHASES]))
    if vert.size == 0:
        return out, 0.0
    # The slot of every vertical sample: the move's source while picking/lifting, else its destination.
    src = np.array([(m.from_tower, m.from_height) for m in moves], dtype=int).reshape(-1, 2)
    dst = np.array([(m.to_tower, m.to_height) for m in moves], dtype=int).reshape(-1, 2)
    mi = tr.move_index[vert]
    at_src = np.isin(tr.phase[vert], [int(Phase.DESCEND_PICK), int(Phase.LIFT)])
    slot = np.where(at_src[:, None], src[mi], dst[mi])
    line_xy = np.array([[contact_point_world(station, t, h)[:2] for h in range(station.n_heights)]
                        for t in range(station.n_towers)])
    p = tcp_positions_world(station, tr.q[vert])
    dev = np.linalg.norm(p[:, :2] - line_xy[slot[:, 0], slot[:, 1]], axis=1)
    # Placing onto a stack: within the band above the contact pose, the band's own (tighter) tolerance.
    allowed = np.full(len(vert), tol_m)
    placing = tr.phase[vert] == int(Phase.DESCEND_PLACE)
    z_on = np.array([[contact_point_world(station, t, h)[2] for h in range(station.n_heights)]
                     for t in range(station.n_towers)])[slot[:, 0], slot[:, 1]]
    for i in np.flatnonzero(placing):
        band = place_band(int(slot[i, 1]))
        if band is not None and p[i, 2] <= z_on[i] + band[0]:
            allowed[i] = min(tol_m, band[1])
    for i in np.flatnonzero(dev > allowed)[:5]:
        k, (tower, height) = vert[i], slot[i]
        band = place_band(int(height))
        where = (f" within {band[0] * 1e3:.1f} mm above the contact pose (placing onto a stack)"
                 if band is not None and allowed[i] < tol_m else "")
        out.append(f"suction point {dev[i] * 1e3:.2f} mm off the vertical line of tower {tower + 1} height "
                   f"{height + 1} at t = {tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name}, move "
                   f"{tr.move_index[k] + 1}){where}; allowed {allowed[i] * 1e3:.1f} mm")
    return out, float(np.max(dev))
