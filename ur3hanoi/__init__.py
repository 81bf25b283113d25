"""ur3hanoi: kinematics toolkit for the UR3 Tower of Hanoi lab.

The package follows the data flow, one folder per concept (``docs/design.md``): :mod:`~ur3hanoi.io` (the one YAML
loader, schemas, atomic writes, the user cache), :mod:`~ur3hanoi.robot` (the arm: registry, DH, URDF, Pinocchio
model, IK), :mod:`~ur3hanoi.station` (a calibrated layout and its grid), :mod:`~ur3hanoi.tables` (the IK table
and ``lab2_data.yaml``), :mod:`~ur3hanoi.calibrate` (a station from taught poses), :mod:`~ur3hanoi.audit`
(hand-recorded tables checked), :mod:`~ur3hanoi.plan` (Ruckig plans), :mod:`~ur3hanoi.sim` (MuJoCo),
:mod:`~ur3hanoi.interface` (the ROS 1 and ROS 2 servers and clients), :mod:`~ur3hanoi.replay`,
:mod:`~ur3hanoi.plots` and :mod:`~ur3hanoi.cli` (the ``ur3hanoi`` command).

The names a notebook or a script uses most are importable from here (``from ur3hanoi import load_station``); each
is imported from its module on first use, so ``import ur3hanoi`` costs nothing (every command imports it).
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from ur3hanoi.audit import audit_table
    from ur3hanoi.calibrate import fit_station
    from ur3hanoi.calibrate.taught import load_taught, taught_from_table
    from ur3hanoi.errors import SuctionFaultError, Ur3HanoiError
    from ur3hanoi.hanoi import solve_hanoi
    from ur3hanoi.io.resources import stations_dir
    from ur3hanoi.plan import Phase, PlanConfig, plan_solve
    from ur3hanoi.robot.dh import dh_fk
    from ur3hanoi.robot.ik import analytic_ik, branch_of, solve_on_branch
    from ur3hanoi.robot.ik_solvers import make_solver, pose_errors
    from ur3hanoi.robot.model import T_BASELINK_BASE, load_ur3
    from ur3hanoi.sim import Faults, build_task_scene, run_plan
    from ur3hanoi.station.calibration import Station, load_station
    from ur3hanoi.station.grid import ABOVE, ON, T_base_tcp, grid_targets_world, pose_label
    from ur3hanoi.tables import read_recorded_table, read_table, write_table
    from ur3hanoi.tables.ik_table import check_table, generate_table
    from ur3hanoi.version import __version__

_HOME: dict[str, str] = {
    "audit_table": "audit", "fit_station": "calibrate",
    **dict.fromkeys(("load_taught", "taught_from_table"), "calibrate.taught"),
    **dict.fromkeys(("SuctionFaultError", "Ur3HanoiError"), "errors"), "solve_hanoi": "hanoi",
    "stations_dir": "io.resources",
    **dict.fromkeys(("Phase", "PlanConfig", "plan_solve"), "plan"),
    "dh_fk": "robot.dh", **dict.fromkeys(("analytic_ik", "branch_of", "solve_on_branch"), "robot.ik"),
    **dict.fromkeys(("make_solver", "pose_errors"), "robot.ik_solvers"),
    **dict.fromkeys(("T_BASELINK_BASE", "load_ur3"), "robot.model"),
    **dict.fromkeys(("Faults", "build_task_scene", "run_plan"), "sim"),
    **dict.fromkeys(("Station", "load_station"), "station.calibration"),
    **dict.fromkeys(("ABOVE", "ON", "T_base_tcp", "grid_targets_world", "pose_label"), "station.grid"),
    **dict.fromkeys(("read_recorded_table", "read_table", "write_table"), "tables"),
    **dict.fromkeys(("check_table", "generate_table"), "tables.ik_table"),
    "__version__": "version",
}
"""The module (under ``ur3hanoi.``) that defines each name of the package's own API."""

__all__ = [
    "ABOVE",
    "ON",
    "T_BASELINK_BASE",
    "Faults",
    "Phase",
    "PlanConfig",
    "Station",
    "SuctionFaultError",
    "T_base_tcp",
    "Ur3HanoiError",
    "__version__",
    "analytic_ik",
    "audit_table",
    "branch_of",
    "build_task_scene",
    "check_table",
    "dh_fk",
    "fit_station",
    "generate_table",
    "grid_targets_world",
    "load_station",
    "load_taught",
    "load_ur3",
    "make_solver",
    "plan_solve",
    "pose_errors",
    "pose_label",
    "read_recorded_table",
    "read_table",
    "run_plan",
    "solve_hanoi",
    "solve_on_branch",
    "stations_dir",
    "taught_from_table",
    "write_table",
]


def __getattr__(name: str) -> Any:
    """The public name ``name``, imported from its module on first use."""
    module = _HOME.get(name)
    if module is None:
        raise AttributeError(f"module 'ur3hanoi' has no attribute {name!r}")
    value = getattr(importlib.import_module(f"ur3hanoi.{module}"), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted({*globals(), *_HOME})
