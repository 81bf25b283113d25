"""The stop-and-go references a plan is measured against, between the same waypoints and dwells.

- :func:`stop_and_go_motion_s`, the honest baseline (``Plan.stop_and_go_duration_s``): joint-space Ruckig from
  rest to rest between consecutive waypoints (home, above, on, above, [over ...], above, on, above, ..., home)
  under the same limits. It ignores the vertical line (a joint-space approach leaves it by 3-10 mm), so it is
  faster than any motion that keeps the line: the plan must beat it anyway.
- :func:`exact_vertical_motion_s` (``Plan.exact_vertical_stop_and_go_duration_s``): the same, with every approach
  and retreat following the vertical line exactly, timed by a 1-DoF Ruckig of the path coordinate under limits
  constant along the path (:class:`~ur3hanoi.plan.motion.vertical.PathLimits`): the reference this project used before
  the honest one, reported for comparison.

Both are motion times [s] (dwells excluded).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.route.builder import Hop
from ur3hanoi.plan.route.connections import StationPlanner


def _waypoints(planner: StationPlanner, hop: Hop) -> list[FloatArray]:
    """The joint waypoints [rad] of a hop's motion across: above(slot0) or home, any over points, above(slot1)
    or home."""
    qs = [planner.q_above(hop.slot0)]
    if hop.over0 is not None and hop.slot0 is not None:
        qs.append(planner.over_pose(hop.slot0, hop.over0))
    if hop.over1 is not None and hop.slot1 is not None:
        qs.append(planner.over_pose(hop.slot1, hop.over1))
    qs.append(planner.q_above(hop.slot1))
    return qs


def _motion_s(planner: StationPlanner, hops: Sequence[Hop], exact_vertical: bool) -> float:
    total = 0.0
    for hop in hops:
        qs = _waypoints(planner, hop)
        total += sum(planner.rest_to_rest(a, b) for a, b in itertools.pairwise(qs))
        for slot in (hop.slot0, hop.slot1):
            if slot is None:
                continue
            if exact_vertical:
                total += planner.exact_vertical_leg(slot)
            else:
                total += planner.rest_to_rest(planner.q_above(slot), planner.wp.table[slot[0], slot[1], 0])
    return total


def stop_and_go_motion_s(planner: StationPlanner, hops: Sequence[Hop]) -> float:
    """Motion time [s] of the honest baseline: joint-space rest-to-rest between the plan's waypoints."""
    return _motion_s(planner, hops, exact_vertical=False)


def exact_vertical_motion_s(planner: StationPlanner, hops: Sequence[Hop]) -> float:
    """Motion time [s] of stop-and-go with approach and retreat on the exact vertical line (constant path limits)."""
    return _motion_s(planner, hops, exact_vertical=True)
