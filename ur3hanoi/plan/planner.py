"""The planning pipeline: hops -> connections (chained Ruckig segments) -> samples -> safety checks -> :class:`Plan`.

Per station and planning limits, the legs and connections are built once and cached
(:func:`~ur3hanoi.plan.route.connections.station_planner`): the first plan on a station pays the set-up (IK table,
vertical paths, the legs and connections it uses), later plans reuse everything they share with it.
"""

from __future__ import annotations

import time
from collections.abc import Sequence

from ur3hanoi.errors import PlanError
from ur3hanoi.hanoi import Move, check_sequence, solve_hanoi
from ur3hanoi.plan.baseline.stop_and_go import exact_vertical_motion_s, stop_and_go_motion_s
from ur3hanoi.plan.checks.limits import check_limits
from ur3hanoi.plan.checks.stored import check_segments
from ur3hanoi.plan.checks.suction import check_suction_hold
from ur3hanoi.plan.checks.vertical import check_vertical
from ur3hanoi.plan.motion.sampling import sample
from ur3hanoi.plan.motion.waypoints import build_waypoints
from ur3hanoi.plan.route.builder import SegmentBuilder, plan_hops
from ur3hanoi.plan.types import Plan, PlanConfig
from ur3hanoi.station.calibration import Station


def plan_moves(station: Station, moves: Sequence[Move], config: PlanConfig | None = None, *, start: int = 0,
               end: int = 1, n_blocks: int | None = None) -> Plan:
    """Time-parameterize a given (legal) move sequence on ``station``; see :func:`plan_solve`."""
    config = config or PlanConfig()
    config.validate()
    n_blocks = n_blocks if n_blocks is not None else (max(m.block for m in moves) + 1 if moves else 0)
    timings: dict[str, float] = {}
    t0 = time.perf_counter()
    build_waypoints(station)
    timings["waypoints"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    builder = SegmentBuilder(station, config)
    limits = builder.limits
    ruckig_before = builder.planner.ruckig_seconds
    hops = plan_hops(station, moves, n_blocks, start, config.clearance_m)
    segments = builder.build(hops)
    timings["build"] = time.perf_counter() - t0
    timings["ruckig"] = builder.planner.ruckig_seconds - ruckig_before
    t0 = time.perf_counter()
    dwell_total = 2 * len(moves) * config.dwell_s
    stop_go = stop_and_go_motion_s(builder.planner, hops) + dwell_total
    exact_vertical = exact_vertical_motion_s(builder.planner, hops) + dwell_total
    timings["baselines"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    tr = sample(segments, config.rate_hz)
    timings["sampling"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    violations = check_limits(tr, segments, limits, station.limits.q_min, station.limits.q_max)
    vert, _ = check_vertical(tr, moves, station, config.vertical_tol_m)
    violations += vert
    violations += check_suction_hold(tr, station, config.suction_hold_mps2)[0]
    timings["checks"] = time.perf_counter() - t0
    if config.check_collisions and moves:
        t0 = time.perf_counter()
        violations += check_segments(segments, moves, station, n_blocks, start, config, limits, tr)
        timings["collision"] = time.perf_counter() - t0
    duration = segments[-1].t_end
    plan = Plan(station=station, moves=tuple(moves), trajectory=tr, stop_and_go_duration_s=stop_go, config=config,
                segments=tuple(segments), limits=limits, violations=tuple(violations), duration_s=duration,
                dwell_total_s=dwell_total, stop_and_go_motion_s=stop_go - dwell_total, start=start, end=end,
                n_blocks=n_blocks, timings_s=timings, exact_vertical_stop_and_go_duration_s=exact_vertical,
                exact_vertical_stop_and_go_motion_s=exact_vertical - dwell_total,
                vertical_deviation_m=max((leg.deviation_m for leg in builder.legs_used), default=0.0))
    if violations and config.raise_on_violation:
        more = f" (+{len(violations) - 1} more)" if len(violations) > 1 else ""
        raise PlanError(f"plan on {station.name} violates a safety check: {violations[0]}{more}")
    return plan


def plan_solve(station: Station, start: int, end: int, n_blocks: int, config: PlanConfig | None = None) -> Plan:
    """Solve the Hanoi instance (0-based towers) and time-parameterize the whole motion with Ruckig.

    Raises:
        PuzzleError: invalid instance (start == end, tower outside the grid, too many blocks).
        PlanError: Ruckig failure or a safety check violation (limits, vertical approach, clearance).
        IKError: a waypoint is unreachable on the home branch.
    """
    moves = solve_hanoi(n_blocks, start, end, station.n_towers, station.n_heights)
    check_sequence(moves, n_blocks, start, end, station.n_towers, station.n_heights)
    return plan_moves(station, moves, config, start=start, end=end, n_blocks=n_blocks)
