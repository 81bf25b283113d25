"""A plan that follows a given lab table: the lab program's joint moves between the table's own waypoints.

:func:`plan_table` is what ``ur3hanoi solve --table`` executes: not the waypoints ur3hanoi would generate, but the
joint angles of a given ``Q[tower][height][k]`` (a hand-recorded or another tool's table), moved through the way
the lab program does it. Per move (0-based slots, ``k = 0`` on, ``k = 1`` above)::

    above(src) -> on(src) -> suction on, dwell -> above(src) -> above(dst) -> on(dst) -> suction off, dwell
    -> above(dst)

from home at the start and back home at the end. Every move between two waypoints is one rest-to-rest joint-space
Ruckig segment (:func:`ur3hanoi.plan.to_pose`: time-optimal, jerk-limited, time-synchronized, under the UR3's
limits scaled by ``PlanConfig.speed``), sampled at ``PlanConfig.rate_hz`` into the same :class:`Plan` /
:class:`Trajectory` contract :func:`ur3hanoi.sim.run_plan` executes (phases, move index, commanded suction).

What is checked, and what is not:

- Every sample against the joint position, velocity, acceleration and jerk limits (:func:`check_limits`).
- No vertical-line corridor: a hand table's "above" need not be exactly above its "on" pose, and the straight
  joint-space move between them is what the lab program does anyway. No clearance check either: the simulation
  shows what a table does (a missed block halts, a block knocked over is reported by the final check).
- Missing entries (NaN rows: ``null`` in the file) that the solve visits raise :class:`TableError` naming them;
  missing entries the solve does not visit are fine.

Segment targets name the table entry a segment ends at, 1-based with the file's 0-based list index,
``"table entry tower 1 height 3 on (Q[0][2][0])"``; the executor's fault messages quote them.
"""

from __future__ import annotations

import time

import numpy as np
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import PlanError, TableError, printable
from ur3hanoi.hanoi import check_sequence, solve_hanoi, validate_instance
from ur3hanoi.plan.checks.limits import check_limits
from ur3hanoi.plan.motion.ruckig import OfflineRuckig
from ur3hanoi.plan.motion.sampling import sample
from ur3hanoi.plan.types import Phase, Plan, PlanConfig, Segment
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON
from ur3hanoi.tables.visits import entry_label, require_entries


def _target(tower: int, height: int, k: int) -> str:
    return f"table entry {entry_label(tower, height, k)}"


def check_table_shape(table: FloatArray, station: Station, where: str = "table") -> None:
    """Raise :class:`TableError` unless ``table`` is (towers, heights, 2, 6) of ``station``'s grid."""
    expected = (station.n_towers, station.n_heights, 2, N_JOINTS)
    if table.shape != expected:
        raise TableError(f"{printable(where)}: the table has shape {table.shape} (towers, heights, poses, joints); "
                         f"calibration {printable(station.name)} needs {expected}")


class _Chain:
    """Rest-to-rest joint segments and dwells laid end to end in time; one Ruckig problem per distinct pair of
    poses (a solve revisits the same few pairs, and each problem is deterministic in its inputs)."""

    def __init__(self, config: PlanConfig, station: Station) -> None:
        self.limits = config.limits(station)
        self.ruckig = OfflineRuckig(self.limits.v_max, self.limits.a_max, self.limits.j_max)
        self.dwell_s = config.dwell_s
        self.segments: list[Segment] = []
        self.t_end = 0.0
        self._memo: dict[tuple[bytes, bytes], RuckigTrajectory] = {}
        self._zero = np.zeros(N_JOINTS)
        self._zeros = [0.0] * N_JOINTS

    def move(self, phase: Phase, move_index: int, q0: FloatArray, q1: FloatArray, target: str) -> None:
        key = (q0.tobytes(), q1.tobytes())
        traj = self._memo.get(key)
        if traj is None:
            z = self._zeros
            sol = self.ruckig.solve(q0, z, z, q1, z, z)
            if sol.trajectory is None:
                raise TableError(f"the joint move to {target} could not be planned from "
                                 f"{np.round(q0, 4).tolist()} rad: {sol.reason}")
            traj = self._memo[key] = sol.trajectory
        if traj.duration <= 0.0:  # the same pose twice (e.g. an "above" shared by two entries): nothing to move
            return
        self._add(Segment(phase, move_index, self.t_end, traj.duration, q0, q1, self._zero, self._zero, target,
                          traj))

    def dwell(self, phase: Phase, move_index: int, q: FloatArray, target: str) -> None:
        self._add(Segment(phase, move_index, self.t_end, self.dwell_s, q, q, self._zero, self._zero, target))

    def _add(self, seg: Segment) -> None:
        self.segments.append(seg)
        self.t_end += seg.duration


def plan_table(station: Station, table: FloatArray, start: int, end: int, n_blocks: int,
               config: PlanConfig | None = None, *, where: str = "table") -> Plan:
    """Plan the Hanoi solve (0-based towers) through the waypoints of ``table``, as the lab program moves.

    Args:
        station: the station the table is executed on (home pose, grid size, joint limits).
        table: ``Q[tower, height, k]`` (towers, heights, 2, 6) [rad], controller convention; NaN rows are
            missing entries.
        start, end, n_blocks: the instance (0-based towers).
        config: speed, rate, dwell and limit overrides; ``pass_through``, ``via_speeds``/``via_accels``,
            ``vertical_tol_m`` and the clearance settings do not apply (every waypoint is a stop, nothing is
            checked against a line).
        where: how the table is named in messages (e.g. ``"lab2_data.yaml:sim_pos"``).

    Returns:
        The plan; ``stop_and_go_duration_s`` equals ``duration_s`` (the plan stops at every waypoint).

    Raises:
        TableError: the table does not fit the station's grid, lacks an entry the solve visits (all of them are
            named), or a joint move between two entries cannot be planned.
        PuzzleError: invalid instance.
        PlanError: a sample leaves a joint position, velocity, acceleration or jerk limit (``raise_on_violation``;
            else the violations are in ``Plan.violations``).
    """
    config = config or PlanConfig()
    config.validate()
    table = np.asarray(table, dtype=float)
    check_table_shape(table, station, where)
    validate_instance(n_blocks, start, end, station.n_towers, station.n_heights)
    moves = solve_hanoi(n_blocks, start, end, station.n_towers, station.n_heights)
    check_sequence(moves, n_blocks, start, end, station.n_towers, station.n_heights)
    require_entries(table, moves, where)  # the rule of every table follower (ros-solve's too)

    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    chain = _Chain(config, station)
    q_home = station.q_home_array
    q_prev = q_home
    for mi, m in enumerate(moves):
        src, dst = (m.from_tower, m.from_height), (m.to_tower, m.to_height)
        # The retreat after a place belongs to that move; the approach to the next pick starts this one.
        chain.move(Phase.TRANSIT, mi, q_prev, table[src][ABOVE], _target(*src, ABOVE))
        chain.move(Phase.DESCEND_PICK, mi, table[src][ABOVE], table[src][ON], _target(*src, ON))
        chain.dwell(Phase.GRASP_DWELL, mi, table[src][ON], _target(*src, ON))
        chain.move(Phase.LIFT, mi, table[src][ON], table[src][ABOVE], _target(*src, ABOVE))
        chain.move(Phase.CARRY, mi, table[src][ABOVE], table[dst][ABOVE], _target(*dst, ABOVE))
        chain.move(Phase.DESCEND_PLACE, mi, table[dst][ABOVE], table[dst][ON], _target(*dst, ON))
        chain.dwell(Phase.RELEASE_DWELL, mi, table[dst][ON], _target(*dst, ON))
        chain.move(Phase.RETREAT, mi, table[dst][ON], table[dst][ABOVE], _target(*dst, ABOVE))
        q_prev = table[dst][ABOVE]
    chain.move(Phase.HOME, -1, q_prev, q_home, "home")
    segments = chain.segments
    timings["build"] = time.perf_counter() - t0
    timings["ruckig"] = chain.ruckig.seconds
    t0 = time.perf_counter()
    tr = sample(segments, config.rate_hz)
    timings["sampling"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    lim = station.limits
    violations = check_limits(tr, segments, chain.limits, lim.q_min, lim.q_max)
    timings["checks"] = time.perf_counter() - t0
    duration = chain.t_end
    dwell_total = 2 * len(moves) * config.dwell_s
    plan = Plan(station=station, moves=tuple(moves), trajectory=tr, stop_and_go_duration_s=duration, config=config,
                segments=tuple(segments), limits=chain.limits, violations=tuple(violations), duration_s=duration,
                dwell_total_s=dwell_total, stop_and_go_motion_s=duration - dwell_total, start=start, end=end,
                n_blocks=n_blocks, timings_s=timings)
    if violations and config.raise_on_violation:
        more = f" (+{len(violations) - 1} more)" if len(violations) > 1 else ""
        raise PlanError(f"the plan through {printable(where)} violates a limit: {violations[0]}{more}")
    return plan
