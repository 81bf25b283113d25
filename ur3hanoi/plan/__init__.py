"""Motion plan of a Hanoi solve: waypoints from the table, time-parameterized by Ruckig under the UR3's limits.

Entry points: :func:`plan_solve` (solve the instance, then plan it) and :func:`plan_moves` (plan a given move
sequence); both return a :class:`Plan`. Everything listed in ``__all__`` is importable from ``ur3hanoi.plan``.

Package map (dependencies flow downward only; each module is one concept):

- :mod:`~ur3hanoi.plan.types`: the data types: :class:`Phase`, :class:`Trajectory`, :class:`KinematicLimits`,
  :class:`PlanConfig`, :class:`Segment`, :class:`Plan`.
- :mod:`~ur3hanoi.plan.kinematics`: the suction point's world position and acceleration, vectorised.
- ``motion/``: how the arm moves.
  :mod:`~ur3hanoi.plan.motion.ruckig` the one Ruckig wrapper (offline; keeps Ruckig's ``Result``);
  :mod:`~ur3hanoi.plan.motion.vertical` a slot's vertical line as a joint path (:class:`VerticalPath`);
  :mod:`~ur3hanoi.plan.motion.sampling` the exact vectorised sampling of the plan at ``rate_hz``;
  :mod:`~ur3hanoi.plan.motion.minimize` SciPy's Nelder-Mead stopped at a lower bound;
  :mod:`~ur3hanoi.plan.motion.legs` approach/retreat legs through interior IK points of the line (method there);
  :mod:`~ur3hanoi.plan.motion.via` the search for a connection's via states at the above poses;
  :mod:`~ur3hanoi.plan.motion.blend` the motion across starting inside the 2 mm corridor.
- :mod:`~ur3hanoi.plan.motion.waypoints`: :func:`build_waypoints`: home, the IK table and every slot's vertical path.
- ``route/``: from dwell to dwell. :mod:`~ur3hanoi.plan.route.connections` the best connection of two slots and
  the per-station cache; :mod:`~ur3hanoi.plan.route.builder` the hops of a move sequence (rising over taller towers)
  and their chained segments.
- ``checks/``: what a plan must satisfy. :mod:`~ur3hanoi.plan.checks.limits` joint limits;
  :mod:`~ur3hanoi.plan.checks.vertical` the 2 mm vertical line; :mod:`~ur3hanoi.plan.checks.suction` what the
  suction holds while carrying; :mod:`~ur3hanoi.plan.checks.collision` the clearance rules and
  :func:`check_collisions`; :mod:`~ur3hanoi.plan.checks.clearance` the planner's per-segment clearance check;
  :mod:`~ur3hanoi.plan.checks.stored` its result in the user's cache.
- ``baseline/``: :mod:`~ur3hanoi.plan.baseline.lab_program` the lab's own program on the same moves (movej per
  waypoint, its waits); :mod:`~ur3hanoi.plan.baseline.stop_and_go` the stop-and-go references between the same
  waypoints.
- :mod:`~ur3hanoi.plan.export`: :func:`trajectory_csv` and :func:`plan_json_dict` (what ``ur3hanoi plan`` prints).
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
acceleration 4/8 rad/s^2 and jerk 500/1000 rad/s^3 (joints 1-3 / 4-6, ``ur3hanoi.robot.model.DEFAULT_JERK_MAX``: the
``JointLimits`` defaults; UR does not publish them). ``PlanConfig.speed`` scales all three; each can be
overridden. Every sample is checked against them, against what the suction holds while carrying
(:func:`~ur3hanoi.plan.checks.suction.check_suction_hold`, ``PlanConfig.suction_hold_mps2``), every sample of a
vertical phase against the vertical line (``PlanConfig.vertical_tol_m``, 2 mm; every leg
also by forward kinematics at 1 kHz where it is built), and the clearances by the planner's segment check
(:mod:`ur3hanoi.plan.checks.clearance`; :func:`check_collisions` checks any sampled trajectory by the same rules).

Speed (see ``bench/REPORT.md``): the motion is measured against the honest stop-and-go baseline (joint-space
Ruckig from rest to rest between the same waypoints, same limits and dwells: ``Plan.stop_and_go_duration_s``);
the exact-vertical stop-and-go the project used to compare with is ``Plan.exact_vertical_stop_and_go_duration_s``.

Names of :mod:`ur3hanoi.tables.visits` and :mod:`~ur3hanoi.plan.table_plan` are loaded on first use: a plan of a
station does not read lab files, and importing ``ur3hanoi.tables`` (its reader and writer) is a tenth of a cold
``ur3hanoi plan``'s imports.
"""

from importlib import import_module
from typing import TYPE_CHECKING

from ur3hanoi.plan.checks.collision import CollisionScene, check_collisions
from ur3hanoi.plan.checks.limits import check_limits
from ur3hanoi.plan.checks.vertical import check_vertical
from ur3hanoi.plan.export import plan_json_dict, trajectory_csv
from ur3hanoi.plan.kinematics import tcp_positions_world
from ur3hanoi.plan.motion.ruckig import OfflineRuckig, RuckigSolution, control_samples, to_pose, to_rest
from ur3hanoi.plan.motion.sampling import sample
from ur3hanoi.plan.motion.waypoints import Waypoints, build_waypoints
from ur3hanoi.plan.planner import plan_moves, plan_solve
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
    VerticalPath,
)

if TYPE_CHECKING:
    from ur3hanoi.plan.table_plan import check_table_shape, plan_table
    from ur3hanoi.tables.visits import entries_visited, entry_label, missing_entries

_LAZY = {"entries_visited": "ur3hanoi.tables.visits", "entry_label": "ur3hanoi.tables.visits",
         "missing_entries": "ur3hanoi.tables.visits", "check_table_shape": "ur3hanoi.plan.table_plan",
         "plan_table": "ur3hanoi.plan.table_plan"}


def __getattr__(name: str) -> object:
    """The names of :data:`_LAZY`, imported on first use."""
    if name in _LAZY:
        value = getattr(import_module(_LAZY[name]), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


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
    "plan_json_dict",
    "plan_moves",
    "plan_solve",
    "plan_table",
    "sample",
    "tcp_positions_world",
    "to_pose",
    "to_rest",
    "trajectory_csv",
]
