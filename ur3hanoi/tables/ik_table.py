"""Waypoint generation: the joint table ``Q[tower][height][k]`` of a station by IK, and its FK check.

``Q[t][h][0]`` is the contact ("on") pose of tower ``t`` at height ``h`` and ``Q[t][h][1]`` the pose above it:
six joint angles [rad], controller convention, on the home configuration's branch (see
:func:`ur3hanoi.robot.ik.solve_on_branch`). The Cartesian targets come from :mod:`ur3hanoi.station.grid`. Reading and
writing the lab's file (``lab2_data.yaml``) is :mod:`ur3hanoi.tables`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import TableError, printable
from ur3hanoi.robot.chain import se3_act_inv
from ur3hanoi.robot.ik import branch_of, solve_table_on_branch
from ur3hanoi.robot.ik_solvers import IKResult, IKSolver, make_solver, pose_errors
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import H_world_tcp, T_world_tcp, pose_label


@dataclass(frozen=True)
class Table:
    """A generated table. ``q[tower, height, k]`` are joint angles [rad]; ``results`` the per-pose IK outcomes."""

    station: Station
    q: FloatArray  # shape (n_towers, n_heights, 2, 6)
    results: tuple[IKResult, ...]
    solver: str

    @property
    def max_position_error(self) -> float:
        """Largest IK position error over the table [m]."""
        return max(r.position_error for r in self.results)

    @property
    def max_orientation_error(self) -> float:
        """Largest IK orientation error over the table [rad]."""
        return max(r.orientation_error for r in self.results)


def generate_table(station: Station, solver: str | IKSolver = "pinocchio") -> Table:
    """IK of every grid pose of ``station`` on the home branch (see :func:`ur3hanoi.robot.ik.solve_on_branch`).

    Raises:
        IKError: a pose is unreachable or out of limits; the message names tower, height and on/above.
    """
    if isinstance(solver, str):
        solver = make_solver(solver, load_ur3(station.tool, station.limits, station.robot))
    slots = [(t, h, k) for t in range(station.n_towers) for h in range(station.n_heights) for k in (0, 1)]
    H_world_base = station.H_world_base
    results = solve_table_on_branch(solver, [se3_act_inv(H_world_base, H_world_tcp(station, *s)) for s in slots],
                                    station.q_home_array, [f"{station.source}: {pose_label(*s)}" for s in slots],
                                    branch_of(station.q_home_array, station.robot.dh))
    q = np.array([r.q for r in results]).reshape(station.n_towers, station.n_heights, 2, N_JOINTS)
    return Table(station=station, q=q, results=tuple(results), solver=solver.name)


@dataclass(frozen=True)
class CheckRow:
    """FK error of one table entry against the calibration's intended pose; ``tower``, ``height``, ``k`` are
    0-based indices into ``Q``."""

    tower: int
    height: int
    k: int
    position_error_mm: float
    orientation_error_deg: float
    ok: bool


def check_table(q: FloatArray, station: Station, tol_mm: float = 1.0, tol_deg: float = 0.5,
                where: str = "table") -> list[CheckRow]:
    """FK of every entry of ``q`` (T, H, 2, 6) [rad] vs ``station``'s intended TCP poses, in mm and deg.

    Entries that are NaN (missing, see :class:`ur3hanoi.tables.RecordedTable`) get no row.

    Raises:
        TableError: the table's towers x heights differ from the station's grid.
    """
    if q.shape[:2] != (station.n_towers, station.n_heights):
        raise TableError(
            f"{printable(where)}: table has {q.shape[0]} towers x {q.shape[1]} heights, calibration "
            f"{printable(station.source)} "
            f"has {station.n_towers} x {station.n_heights}"
        )
    robot = load_ur3(station.tool, station.limits, station.robot)
    T_wb = station.T_world_base
    rows = []
    for t in range(q.shape[0]):
        for h in range(q.shape[1]):
            for k in (0, 1):
                if np.isnan(q[t, h, k]).any():
                    continue
                dp, dr = pose_errors(T_wb * robot.fk(q[t, h, k]), T_world_tcp(station, t, h, k))
                mm, deg = dp * 1e3, math.degrees(dr)
                rows.append(CheckRow(t, h, k, mm, deg, mm <= tol_mm and deg <= tol_deg))
    return rows


__all__ = ["CheckRow", "Table", "check_table", "generate_table"]
