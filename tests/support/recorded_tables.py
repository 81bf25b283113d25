"""Synthetic hand-recorded tables: IK of a station's grid poses re-solved at perturbed targets, and gross errors.

A recorded pose is the IK solution (home branch) of the grid pose moved by a random 1..3 mm in a random direction
and turned by a random 0..0.5 deg about a random axis: what jogging the arm by eye gives. Gross errors are applied
to the joint values afterwards, as a person transcribing the pendant would make them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

from ur3hanoi.robot.ik import solve_on_branch
from ur3hanoi.robot.ik_solvers import make_solver
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, ON, T_world_tcp

Slot = tuple[int, int, int]
NOISE_MM = (1.0, 3.0)
TURN_DEG = 0.5


def _unit(rng: np.random.Generator) -> np.ndarray:
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def recorded_q(station: Station, rng: np.random.Generator | None, noise_mm: tuple[float, float] = NOISE_MM,
               turn_deg: float = TURN_DEG) -> np.ndarray:
    """Every grid pose ``(T, H, 2, 6)`` [rad], recorded with noise (exact when ``rng`` is None)."""
    solver = make_solver("pinocchio", load_ur3(station.tool, station.limits))
    q = np.empty((station.n_towers, station.n_heights, 2, 6))
    for t in range(station.n_towers):
        for h in range(station.n_heights):
            for k in (ON, ABOVE):
                target = T_world_tcp(station, t, h, k)
                R, p = target.rotation, target.translation
                if rng is not None:
                    p = p + _unit(rng) * rng.uniform(*noise_mm) * 1e-3
                    R = R @ pin.exp3(_unit(rng) * math.radians(rng.uniform(0.0, turn_deg)))
                T = station.T_world_base.actInv(pin.SE3(R, p))
                q[t, h, k] = solve_on_branch(solver, T, station.q_home_array, label=str((t, h, k))).q
    return q


def typo(q: np.ndarray, slot: Slot, joint: int, delta_deg: float) -> np.ndarray:
    """``q`` with joint ``joint`` (0-based) of ``slot`` off by ``delta_deg``."""
    out = q.copy()
    out[slot][joint] += math.radians(delta_deg)
    return out


def swap(q: np.ndarray, a: Slot, b: Slot) -> np.ndarray:
    out = q.copy()
    out[a], out[b] = q[b].copy(), q[a].copy()
    return out


def duplicate(q: np.ndarray, src: Slot, dst: Slot) -> np.ndarray:
    """``q`` with ``src``'s pose copied into ``dst``."""
    out = q.copy()
    out[dst] = q[src].copy()
    return out


def shared_above(station: Station, q: np.ndarray) -> np.ndarray:
    """``q`` with one above pose per tower, the one of its top height, for every height."""
    out = q.copy()
    for t in range(q.shape[0]):
        out[t, :, ABOVE] = q[t, station.n_heights - 1, ABOVE]
    return out


def table_doc(q: np.ndarray, contact_only: bool = False, missing: Sequence[Slot] = (), alias_shared: bool = True
              ) -> list[Any]:
    """``Q`` as YAML-ready lists: ``[on]`` only per slot when ``contact_only``, ``None`` at ``missing`` slots;
    identical above poses of a tower become one YAML anchor and its aliases when ``alias_shared``."""
    doc: list[Any] = []
    for t in range(q.shape[0]):
        tower: list[Any] = []
        shared: dict[tuple[float, ...], list[float]] = {}
        for h in range(q.shape[1]):
            poses: list[Any] = []
            for k in ((ON,) if contact_only else (ON, ABOVE)):
                vec = [float(v) for v in q[t, h, k]]
                if k == ABOVE and alias_shared:
                    vec = shared.setdefault(tuple(vec), vec)  # the same list object: PyYAML writes an alias
                poses.append(None if (t, h, k) in missing else vec)
            tower.append(poses)
        doc.append(tower)
    return doc


def write_table(path: Path, key: str, doc: list[Any]) -> Path:
    path.write_text(yaml.safe_dump({key: doc}, sort_keys=False))
    return path


# ------------------------------------------------------------------------------------- recorded-like tables
#
# What real hand-recorded tables look like (issue 19): the suction point is jogged onto each block within 1-2 mm,
# the arm arrives at each tower with its own heading (and wrist 3 turned a little more or less per entry), the
# suction axis is off vertical by the same small amount on the whole table (robot base or tool mount) plus a
# fraction of a degree per entry, and the above poses are recorded anywhere 15-60 mm over the top of the stacks.

JITTER_MM = (1.0, 2.0)
"""[mm] how far a recorded suction point is from the block's (random direction)."""
TOWER_HEADING_DEG = 30.0
"""[deg] each tower's arrival heading is the station's tool yaw + U(-30, 30)."""
WRIST3_DEG = 8.0
"""[deg] each entry's heading is its tower's + U(-8, 8) (wrist 3 turned by eye)."""
TABLE_TILT_DEG = 1.5
"""[deg] the whole table's suction axis is off vertical by U(0, 1.5) in a random direction."""
ENTRY_TILT_DEG = 0.7
"""[deg] each entry's suction axis is off the table's by U(0, 0.7) in a random direction."""
ABOVE_MM = (15.0, 60.0)
"""[mm] an above pose is U(15, 60) over the table's top level (the top contact of the stacks)."""
SPACINGS_M = (0.05, 0.15)
"""[m] stacked stations: the gap between neighbouring towers, drawn per gap."""


def _turn_to(axis_from: np.ndarray, axis_to: np.ndarray) -> np.ndarray:
    """The smallest rotation taking unit vector ``axis_from`` to ``axis_to``."""
    w = np.cross(axis_from, axis_to)
    s = float(np.linalg.norm(w))
    if s < 1e-12:
        return np.eye(3)
    return np.asarray(pin.exp3(w / s * math.atan2(s, float(axis_from @ axis_to))))


def _tilted(rng: np.random.Generator, max_deg: float, exact_deg: float | None = None) -> np.ndarray:
    """A rotation about a random horizontal axis by U(0, max_deg) (or ``exact_deg``)."""
    a = rng.uniform(0.0, 2.0 * math.pi)
    deg = rng.uniform(0.0, max_deg) if exact_deg is None else exact_deg
    return np.asarray(pin.exp3(np.array([math.cos(a), math.sin(a), 0.0]) * math.radians(deg)))


def stacked_station(rng: np.random.Generator) -> Station:
    """A lab_real-like stacked station: three towers in a row along y at uneven gaps of 5-15 cm."""
    from dataclasses import replace

    from ur3hanoi.station.calibration import load_station

    base = load_station("lab_real")
    gaps = rng.uniform(*SPACINGS_M, size=base.n_towers - 1)
    y = np.concatenate([[0.0], np.cumsum(gaps)])
    y = y - y.mean() - 0.07 + rng.uniform(-0.02, 0.02)
    x = rng.uniform(0.22, 0.30)
    z = base.tower_origins[0][2] + rng.uniform(-0.002, 0.002)
    return replace(base, tower_origins=tuple((float(x), float(yi), float(z)) for yi in y))


def flat_station() -> Station:
    """The course's flat Gazebo layout (lab_sim)."""
    from ur3hanoi.station.calibration import load_station

    return load_station("lab_sim")


@dataclass(frozen=True)
class RecordedLike:
    """A recorded-like table: its station (the truth), joint values ``q`` (T, H, 2, 6) [rad], and the true suction
    axis of the table (unit vector pointing down, world)."""

    station: Station
    q: np.ndarray
    axis: np.ndarray


def pose_q(station: Station, p_world: np.ndarray, R_world: np.ndarray) -> np.ndarray:
    """Joint values [rad] (home's branch, nearest home) putting the suction point at ``p_world`` [m] with
    orientation ``R_world`` (closed-form IK)."""
    from ur3hanoi.robot.ik import analytic_ik, branch_of, wrap_angle

    robot = load_ur3(station.tool, station.limits)
    home = station.q_home_array
    branch = branch_of(home)
    T_base_tool0 = station.T_world_base.actInv(pin.SE3(R_world, p_world)) * robot.T_tcp_tool0
    sol = analytic_ik(T_base_tool0, only=branch)
    if branch not in sol:
        raise ValueError(f"pose {np.round(p_world, 4).tolist()} unreachable on home's branch")
    return np.asarray(home + wrap_angle(sol[branch] - home))


def R_tcp(heading: float, tilt_deg: float = 0.0, tilt_about: float = 0.0) -> np.ndarray:
    """Suction axis tilted ``tilt_deg`` off straight down (about the horizontal axis at ``tilt_about`` [rad]), TCP x
    along ``heading`` [rad]."""
    from ur3hanoi.station.grid import R_world_tcp_down

    turn = pin.exp3(np.array([math.cos(tilt_about), math.sin(tilt_about), 0.0]) * math.radians(tilt_deg))
    return np.asarray(turn @ R_world_tcp_down(heading))


def recorded_like(station: Station, rng: np.random.Generator, tilted: Slot | None = None,
                  tilt_deg: tuple[float, float] = (5.0, 6.0)) -> RecordedLike:
    """A table as a student records it on ``station`` (see the constants above); with ``tilted``, that entry's
    suction axis is U(5, 6) deg off the table's (a real mistake) while its suction point is still on the block."""
    from ur3hanoi.station.grid import R_world_tcp_down

    table_tilt = _tilted(rng, TABLE_TILT_DEG)
    axis = table_tilt @ np.array([0.0, 0.0, -1.0])
    top = max(T_world_tcp(station, t, station.n_heights - 1, ON).translation[2] for t in range(station.n_towers))
    q = np.empty((station.n_towers, station.n_heights, 2, 6))
    for t in range(station.n_towers):
        tower_heading = station.tool_yaw + math.radians(rng.uniform(-TOWER_HEADING_DEG, TOWER_HEADING_DEG))
        for h in range(station.n_heights):
            for k in (ON, ABOVE):
                p = T_world_tcp(station, t, h, ON).translation.copy()
                if k == ABOVE:
                    p[2] = top + rng.uniform(*ABOVE_MM) * 1e-3
                p = p + _unit(rng) * rng.uniform(*JITTER_MM) * 1e-3
                heading = tower_heading + math.radians(rng.uniform(-WRIST3_DEG, WRIST3_DEG))
                entry = (_tilted(rng, 0.0, rng.uniform(*tilt_deg)) if (t, h, k) == tilted
                         else _tilted(rng, ENTRY_TILT_DEG))
                q[t, h, k] = pose_q(station, p, entry @ table_tilt @ R_world_tcp_down(heading))
    return RecordedLike(station=station, q=q, axis=axis)
