"""Shared by the simulator tests: the shipped stations, the planner's plans cached across test files, and an
independent stop-and-go plan (:func:`simple_plan`)."""

from __future__ import annotations

import itertools
import math
from functools import cache

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import solve_hanoi
from ur3hanoi.plan import Phase, Plan, PlanConfig, Trajectory, plan_solve
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.tables.ik_table import generate_table

STATIONS = {name: load_station(name) for name in ("lab_sim", "lab_real")}
PAIRS = list(itertools.permutations(range(3), 2))
MAX_TRACKING_RAD = math.radians(0.5)


@cache
def planned(name: str, start: int, end: int) -> Plan:
    """The planner's 3-block plan for a shipped station, computed once per session (planning dominates)."""
    return plan_solve(STATIONS[name], start, end, 3)


def quintic_segment(q0: FloatArray, q1: FloatArray, station: Station, speed: float, rate: float
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rest-to-rest quintic (smoothstep) from q0 to q1 within the joint limits, sampled at ``rate`` [Hz]."""
    lim = station.limits
    dq = q1 - q0
    v, a = np.asarray(lim.v_max) * speed, np.asarray(lim.a_max) * speed
    # Quintic peaks: velocity 1.875 |dq| / T, acceleration 5.7735 |dq| / T^2.
    T = float(max(np.max(1.875 * np.abs(dq) / v), np.max(np.sqrt(5.7735 * np.abs(dq) / a)), 1.0 / rate))
    n = max(1, math.ceil(T * rate))
    T = n / rate
    s = np.arange(1, n + 1) / n
    pos = 10 * s**3 - 15 * s**4 + 6 * s**5
    vel = (30 * s**2 - 60 * s**3 + 30 * s**4) / T
    acc = (60 * s - 180 * s**2 + 120 * s**3) / T**2
    jerk = (60 - 360 * s + 360 * s**2) / T**3
    return (q0 + np.outer(pos, dq), np.outer(vel, dq), np.outer(acc, dq), np.outer(jerk, dq))


def simple_plan(station: Station, start: int, end: int, n_blocks: int, config: PlanConfig | None = None) -> Plan:
    """A stop-and-go plan (quintic joint segments through the IK table's waypoints) with the contract's labels:
    a plan independent of :func:`ur3hanoi.plan.plan_solve`, to run the executor on a reference it did not see."""
    cfg = config if config is not None else PlanConfig()
    moves = tuple(solve_hanoi(n_blocks, start, end, station.n_towers, station.n_heights))
    Q = generate_table(station).q
    rate = cfg.rate_hz
    chunks: list[tuple[FloatArray, FloatArray, FloatArray, FloatArray, bool, int, int]] = []
    q_cur = station.q_home_array

    def go(q1: FloatArray, suction: bool, mv: int, phase: Phase) -> None:
        nonlocal q_cur
        p, v, a, j = quintic_segment(q_cur, q1, station, cfg.speed, rate)
        chunks.append((p, v, a, j, suction, mv, int(phase)))
        q_cur = q1

    def dwell(suction: bool, mv: int, phase: Phase) -> None:
        n = max(1, round(cfg.dwell_s * rate))
        z = np.zeros((n, N_JOINTS))
        chunks.append((np.tile(q_cur, (n, 1)), z, z, z, suction, mv, int(phase)))

    for i, mvv in enumerate(moves):
        go(Q[mvv.from_tower, mvv.from_height, 1], False, i, Phase.TRANSIT)
        go(Q[mvv.from_tower, mvv.from_height, 0], False, i, Phase.DESCEND_PICK)
        dwell(True, i, Phase.GRASP_DWELL)
        go(Q[mvv.from_tower, mvv.from_height, 1], True, i, Phase.LIFT)
        go(Q[mvv.to_tower, mvv.to_height, 1], True, i, Phase.CARRY)
        go(Q[mvv.to_tower, mvv.to_height, 0], True, i, Phase.DESCEND_PLACE)
        dwell(False, i, Phase.RELEASE_DWELL)
        go(Q[mvv.to_tower, mvv.to_height, 1], False, i, Phase.RETREAT)
    go(station.q_home_array, False, -1, Phase.HOME)

    z = np.zeros((1, N_JOINTS))
    qs = [station.q_home_array[None, :]] + [c[0] for c in chunks]
    total = sum(len(c[0]) for c in chunks) + 1
    traj = Trajectory(
        rate_hz=rate,
        t=np.arange(total) / rate,
        q=np.vstack(qs),
        qd=np.vstack([z] + [c[1] for c in chunks]),
        qdd=np.vstack([z] + [c[2] for c in chunks]),
        qddd=np.vstack([z] + [c[3] for c in chunks]),
        suction=np.concatenate([[False]] + [np.full(len(c[0]), c[4]) for c in chunks]),
        move_index=np.concatenate([[-1]] + [np.full(len(c[0]), c[5]) for c in chunks]).astype(int),
        phase=np.concatenate([[int(Phase.TRANSIT)]] + [np.full(len(c[0]), c[6]) for c in chunks]).astype(int),
    )
    return Plan(station=station, moves=moves, trajectory=traj, stop_and_go_duration_s=traj.duration_s, config=cfg)
