"""Synthetic hand-recorded tables: IK of a station's grid poses re-solved at perturbed targets, and gross errors.

A recorded pose is the IK solution (home branch) of the grid pose moved by a random 1..3 mm in a random direction
and turned by a random 0..0.5 deg about a random axis: what jogging the arm by eye gives. Gross errors are applied
to the joint values afterwards, as a person transcribing the pendant would make them.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import yaml

from ur3hanoi.grid import ABOVE, ON, T_world_tcp
from ur3hanoi.ik import make_solver, solve_on_branch
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station

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
