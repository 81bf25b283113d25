"""What the suction can hold: while a block is carried, the seal supplies its weight and inertia.

The limit (``PlanConfig.suction_hold_mps2``, default :data:`ur3hanoi.plan.types.SUCTION_HOLD_MPS2`) is measured
against the simulated suction by ``bench/bench_suction_hold.py``. Returns human-readable violations (empty: the
check passed); :func:`ur3hanoi.plan.plan_moves` collects them.
"""

from __future__ import annotations

import numpy as np

from ur3hanoi.plan.kinematics import tcp_accelerations_world
from ur3hanoi.plan.types import Phase, Trajectory
from ur3hanoi.station.calibration import Station

GRAVITY_WORLD = np.array([0.0, 0.0, -9.81])  # [m/s^2]


def check_suction_hold(tr: Trajectory, station: Station, hold_mps2: float) -> tuple[list[str], float]:
    """While a block is carried (LIFT, CARRY, DESCEND_PLACE), the seal must supply the block's weight and inertia:
    ``|a - g|`` of the suction point [m/s^2] (per kg of block) must stay within ``hold_mps2``.

    Returns (violations, worst ``|a - g|`` [m/s^2] over the carrying samples).
    """
    carrying = np.flatnonzero(np.isin(tr.phase, [int(p) for p in Phase if p.carrying]))
    if carrying.size == 0:
        return [], 0.0
    acc = tcp_accelerations_world(station, tr.q[carrying], tr.qd[carrying], tr.qdd[carrying])
    pull = np.linalg.norm(acc - GRAVITY_WORLD, axis=1)
    out: list[str] = []
    for i in np.flatnonzero(pull > hold_mps2)[:1]:
        k = carrying[i]
        n_bad = int(np.count_nonzero(pull > hold_mps2))
        out.append(f"the carried block needs {pull[i]:.1f} m/s^2 of suction (|a - g| of the suction point) at t = "
                   f"{tr.t[k]:.3f} s ({Phase(int(tr.phase[k])).name}, move {tr.move_index[k] + 1}; {n_bad} samples); "
                   f"the suction holds {hold_mps2:.1f} m/s^2: lower the speed or acceleration")
    return out, float(np.max(pull))
