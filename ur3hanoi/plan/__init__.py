"""Motion plan of a Hanoi solve: waypoints from the table, time-parameterized by Ruckig under the UR3's limits.

Entry points: :func:`plan_solve` (solve the instance, then plan it) and :func:`plan_moves` (plan a given move
sequence); both return a :class:`Plan`. Everything listed in ``__all__`` is importable from ``ur3hanoi.plan``.

Module map (dependencies flow downward only):

- :mod:`~ur3hanoi.plan.types`: the data types: :class:`Phase`, :class:`Trajectory`, :class:`KinematicLimits`,
  :class:`PlanConfig`, :class:`Segment`, :class:`Plan`.
- :mod:`~ur3hanoi.plan.ruckig`: the one Ruckig wrapper of the project (offline only, keeps Ruckig's ``Result``):
  :class:`OfflineRuckig`, :class:`RuckigSolution`, :func:`to_rest`, :func:`to_pose`, :func:`control_samples`.
- :mod:`~ur3hanoi.plan.vertical`: a slot's vertical line as a joint-space path (:class:`VerticalPath`), its
  limits (:class:`~ur3hanoi.plan.vertical.PathLimits`) and braking speed.
- :mod:`~ur3hanoi.plan.waypoints`: :func:`build_waypoints`: home, the IK table and every slot's vertical path.
- :mod:`~ur3hanoi.plan.sampling`: :func:`sample`: the exact vectorised re-implementation of Ruckig's
  ``Trajectory.at_time`` that samples the whole plan at ``rate_hz`` (and :func:`~ur3hanoi.plan.sampling.evaluate`
  for one trajectory).
- :mod:`~ur3hanoi.plan.checks`: :func:`check_limits` and :func:`check_vertical` (the 2 mm vertical line).
- :mod:`~ur3hanoi.plan.optimize`: a small deterministic Nelder-Mead minimiser.
- :mod:`~ur3hanoi.plan.legs`: approach/retreat legs: joint-space Ruckig through interior IK points of the vertical
  line, verified by forward kinematics at 1 kHz; the method and why it was chosen are described there.
- :mod:`~ur3hanoi.plan.via`: the search for a connection's via states at the two above poses.
- :mod:`~ur3hanoi.plan.blend`: blending at the above poses: the motion across starts inside the 2 mm corridor.
- :mod:`~ur3hanoi.plan.connections`: :class:`~ur3hanoi.plan.connections.Connection` (exit leg, motion across,
  entry leg) and the per-station cache :func:`~ur3hanoi.plan.connections.station_planner`.
- :mod:`~ur3hanoi.plan.builder`: the hops of a move sequence (rising over taller towers) and the chained segments
  (pass-through or stop-and-go); how the motion is built is described there.
- :mod:`~ur3hanoi.plan.baseline`: the honest stop-and-go baseline and the exact-vertical stop-and-go reference.
- :mod:`~ur3hanoi.plan.collision`: :class:`CollisionScene`, the clearance rules and :func:`check_collisions`
  (clearances of any sampled trajectory).
- :mod:`~ur3hanoi.plan.clearance`: the clearance check the planner runs, once per distinct segment (continuous
  time, resolved to 1 ms).
- :mod:`~ur3hanoi.plan.export`: :func:`trajectory_csv` and the JSON summary behind :meth:`Plan.to_json_dict`
  (what ``ur3hanoi plan`` prints).
- :mod:`~ur3hanoi.plan.planner`: :func:`plan_moves` / :func:`plan_solve`: hops -> connections -> samples ->
  checks -> :class:`Plan`.
- :mod:`~ur3hanoi.plan.table_plan`: :func:`plan_table`: the same :class:`Plan` through the waypoints of a given
  lab table, moved like the lab program (rest-to-rest joint moves; limits checked, no vertical line).

CONTRACT (shared with ur3hanoi.sim; keep these names and meanings):

- :class:`Phase` labels every trajectory sample.
- :class:`Trajectory` holds the samples at ``rate_hz``: ``t`` (N,) [s], ``q``/``qd``/``qdd``/``qddd`` (N, 6)
  [rad, rad/s, rad/s^2, rad/s^3], ``suction`` (N,) bool (commanded suction), ``move_index`` (N,) int (0-based
  index into ``Plan.moves``, -1 before the first move / on the way home), ``phase`` (N,) int (Phase values).
- :class:`Plan`: ``station``, ``moves`` (tuple of hanoi.Move), ``trajectory``, ``stop_and_go_duration_s`` (the
  honest baseline), ``config``.

Limits: velocity from the UR3 datasheet (``JointLimits.ur3().v_max``: pi rad/s joints 1-3, 2pi rad/s joints 4-6);
acceleration 4/8 rad/s^2 and jerk 500/1000 rad/s^3 (joints 1-3 / 4-6, ``ur3hanoi.robot.DEFAULT_JERK_MAX``: the
``JointLimits`` defaults; UR does not publish them). ``PlanConfig.speed`` scales all three; each can be
overridden. Every sample is checked against them, against what the suction holds while carrying
(:func:`~ur3hanoi.plan.checks.check_suction_hold`, ``PlanConfig.suction_hold_mps2``), every sample of a
vertical phase against the vertical line (``PlanConfig.vertical_tol_m``, 2 mm; every leg
also by forward kinematics at 1 kHz where it is built), and the clearances by the planner's segment check
(:mod:`ur3hanoi.plan.clearance`; :func:`check_collisions` checks any sampled trajectory by the same rules).

Speed (see ``bench/REPORT.md``): the motion is measured against the honest stop-and-go baseline (joint-space
Ruckig from rest to rest between the same waypoints, same limits and dwells: ``Plan.stop_and_go_duration_s``);
the exact-vertical stop-and-go the project used to compare with is ``Plan.exact_vertical_stop_and_go_duration_s``.
"""

from ur3hanoi.plan.checks import check_limits, check_vertical, tcp_positions_world
from ur3hanoi.plan.collision import CollisionScene, check_collisions
from ur3hanoi.plan.export import trajectory_csv
from ur3hanoi.plan.planner import plan_moves, plan_solve
from ur3hanoi.plan.ruckig import OfflineRuckig, RuckigSolution, control_samples, to_pose, to_rest
from ur3hanoi.plan.sampling import sample
from ur3hanoi.plan.table_plan import check_table_shape, entries_visited, entry_label, missing_entries, plan_table
from ur3hanoi.plan.types import (
    DEFAULT_VIA_ACCELS,
    DEFAULT_VIA_SPEEDS,
    DWELL_PHASES,
    SUCTION_PHASES,
    VERTICAL_PHASES,
    KinematicLimits,
    Phase,
    Plan,
    PlanConfig,
    Segment,
    Trajectory,
)
from ur3hanoi.plan.vertical import VerticalPath
from ur3hanoi.plan.waypoints import Waypoints, build_waypoints

__all__ = [
    "DEFAULT_VIA_ACCELS",
    "DEFAULT_VIA_SPEEDS",
    "DWELL_PHASES",
    "SUCTION_PHASES",
    "VERTICAL_PHASES",
    "CollisionScene",
    "KinematicLimits",
    "OfflineRuckig",
    "Phase",
    "Plan",
    "PlanConfig",
    "RuckigSolution",
    "Segment",
    "Trajectory",
    "VerticalPath",
    "Waypoints",
    "build_waypoints",
    "check_collisions",
    "check_limits",
    "check_table_shape",
    "check_vertical",
    "control_samples",
    "entries_visited",
    "entry_label",
    "missing_entries",
    "plan_moves",
    "plan_solve",
    "plan_table",
    "sample",
    "tcp_positions_world",
    "to_pose",
    "to_rest",
    "trajectory_csv",
]
