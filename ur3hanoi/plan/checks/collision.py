"""Clearance checks of a sampled plan: the UR3's collision meshes, the suction cup and the carried block against
the table and the resting blocks (Pinocchio geometry, coal distances), decimated with a proven margin.

The rules (which clearances are required in which phase, and which are excluded as contact by design) are
:func:`clearance_rules` over the resting blocks of :func:`resting_blocks`; see :class:`CollisionScene` for the
geometry, the required distances and the decimation argument. :func:`check_collisions` checks a sampled
trajectory (any trajectory); the planner checks its segments with :mod:`ur3hanoi.plan.checks.clearance`, which
applies the same rules once per distinct segment.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import Move, stacks_before_moves
from ur3hanoi.plan.checks.geometry import robot_geometry
from ur3hanoi.plan.types import DWELL_PHASES, VERTICAL_PHASES, KinematicLimits, Phase, PlanConfig, Trajectory
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import R_world_tcp_down, block_center_world, table_z

if TYPE_CHECKING:
    import pinocchio as pin

Slot = tuple[int, int]  # (tower, height), 0-based
Pair = tuple[tuple[int, int], float]  # (geometry ids, required distance [m])
MAX_REPORTED = 5  # violations reported per plan

# Phases in which the cup touches the block of the move (picking it, or just having placed it).
_CUP_ON_MOVED_BLOCK = (Phase.DESCEND_PICK, Phase.GRASP_DWELL, Phase.RELEASE_DWELL, Phase.RETREAT)


class CollisionScene:
    """Pinocchio GeometryModel of the UR3's URDF collision meshes plus coal boxes: the table, the resting blocks,
    the carried block (attached to the suction point) and a small suction cup at the TCP.

    Distances come from ``pin.computeDistance`` (coal); the robot's meshes are replaced by their convex hulls
    (conservative, much faster). Required distances: robot geometry and carried block
    above the table (> 0), robot geometry clear of resting blocks (> 0), carried block >= ``clearance_m`` from
    every other block. Pairs excluded, and why:

    - base_link vs table: the robot is mounted on the table.
    - cup vs the block being picked (descend/grasp) or just placed (release/retreat): contact by design.
    - carried block vs the block under it (stacked layout) during lift / descend-place, and vs the table during
      lift / descend-place: the block rests on them at contact.
    - cup vs table during the vertical and dwell phases: the cup is at contact there.

    Decimation (proof sketch): every point of the robot and of the carried block moves at most
    ``sum_i |qd_i| R_i`` [m/s], with ``R_i`` a bound on the distance from joint i's origin to any geometry
    downstream of it (sum of the following joint offsets plus the geometry's offset and bounding radius). Over a
    coarse interval [t_a, t_b] no point is farther than ``delta = sum_i max|qd_i| R_i (t_b - t_a) / 2`` from its
    position at the nearer end (max over the interval's samples plus a_max times half a sample step), and a
    distance between two bodies changes at most by the displacement of their points. A pair whose distance
    exceeds ``required + delta`` at both ends is therefore fine at every sample in between; otherwise every
    sample of the interval is checked.
    """

    CUP_RADIUS_M = 0.01
    CUP_LENGTH_M = 0.02

    def __init__(self, station: Station, n_blocks: int) -> None:
        import coal
        import pinocchio as pin

        from ur3hanoi.robot.model import T_BASELINK_BASE

        self.station = station
        robot = load_ur3(station.tool, station.limits, station.robot)
        self.robot = robot
        self.model = robot.model
        self.data = self.model.createData()

        gm = robot_geometry(robot)  # from the user's cache after the first build
        self.robot_geoms = list(range(len(gm.geometryObjects)))
        names = [g.name for g in gm.geometryObjects]
        self.base_geom = names.index("base_link_0") if "base_link_0" in names else -1
        T_baselink_world = T_BASELINK_BASE * station.T_world_base.inverse()
        self.T_baselink_world = T_baselink_world
        fid = robot.frame_ids["tcp"]
        frame = self.model.frames[fid]
        joint6 = frame.parentJoint
        T_j6_tcp = frame.placement
        # Suction cup: a short cylinder above the suction point (tcp z points into the block).
        cup = pin.GeometryObject("cup", joint6, fid, T_j6_tcp * pin.SE3(np.eye(3), np.array(
            [0.0, 0.0, -0.5 * self.CUP_LENGTH_M])), coal.Cylinder(self.CUP_RADIUS_M, self.CUP_LENGTH_M))
        self.cup = gm.addGeometryObject(cup)
        s = station.block_size
        # Block centre seen from the TCP: contact_depth - s/2 above it, i.e. along tcp -z.
        T_tcp_block = pin.SE3(np.eye(3), np.array([0.0, 0.0, -(station.contact_depth - 0.5 * s)]))
        self.carried = gm.addGeometryObject(pin.GeometryObject("carried_block", joint6, fid, T_j6_tcp * T_tcp_block,
                                                               coal.Box(s, s, s)))
        tz = table_z(station)
        table = pin.GeometryObject("table", 0, 0, T_baselink_world * pin.SE3(np.eye(3), np.array(
            [0.0, 0.0, tz - 0.05])), coal.Box(4.0, 4.0, 0.1))
        self.table = gm.addGeometryObject(table)
        self.blocks = []
        for b in range(n_blocks):
            self.blocks.append(gm.addGeometryObject(pin.GeometryObject(f"block_{b}", 0, 0, pin.SE3.Identity(),
                                                                       coal.Box(s, s, s))))
        self.gm = gm
        self.pairs: dict[tuple[int, int], int] = {}
        movers = [*self.robot_geoms, self.cup, self.carried]
        for a in movers:
            for b in [self.table, *self.blocks]:
                self.pairs[(a, b)] = len(self.pairs)
                gm.addCollisionPair(pin.CollisionPair(a, b))
        self.gd = pin.GeometryData(gm)
        self.R = self._reach_bounds()
        self._R_block = R_world_tcp_down(station.tool_yaw)

    def _reach_bounds(self) -> FloatArray:
        """R_i [m]: bound on the distance from joint i's origin to any geometry attached at or after joint i."""
        m = self.model
        offs = [float(np.linalg.norm(m.jointPlacements[j].translation)) for j in range(m.njoints)]
        R = np.zeros(N_JOINTS)
        for i in range(1, N_JOINTS + 1):
            chain = sum(offs[i + 1:])
            extent = 0.0
            for g in self.gm.geometryObjects:
                if g.parentJoint >= i:
                    g.geometry.computeLocalAABB()
                    ext = (float(np.linalg.norm(g.placement.translation))
                           + float(np.linalg.norm(g.geometry.aabb_center)) + float(g.geometry.aabb_radius))
                    extent = max(extent, ext)
            R[i - 1] = chain + extent
        return R

    def place_blocks(self, slots: dict[int, tuple[int, int]]) -> None:
        """Put each resting block (block -> (tower, height)) at its slot; blocks not listed are parked far away."""
        for b, gid in enumerate(self.blocks):
            p = block_center_world(self.station, *slots[b]) if b in slots else np.array([100.0 + 10 * b, 100.0, 100.0])
            self.gm.geometryObjects[gid].placement = self.T_baselink_world * _se3(self._R_block, p)

    def distances(self, q: FloatArray, pairs: Sequence[tuple[int, int]]) -> FloatArray:
        import pinocchio as pin

        pin.updateGeometryPlacements(self.model, self.data, self.gm, self.gd, q)
        return np.array([pin.computeDistance(self.gm, self.gd, self.pairs[p]).min_distance for p in pairs])

    def name(self, gid: int) -> str:
        return self.gm.geometryObjects[gid].name

    def movers(self, mover: str) -> list[int]:
        """Geometry ids of a rule's mover: "robot" (every robot geometry but the base), "cup" or "carried"."""
        if mover == "robot":
            return [g for g in self.robot_geoms if g != self.base_geom]
        return [self.cup] if mover == "cup" else [self.carried]


def _se3(R: FloatArray, p: FloatArray) -> pin.SE3:
    import pinocchio as pin

    return pin.SE3(R, p)


@lru_cache(maxsize=8)
def _collision_scene(station: Station, n_blocks: int) -> CollisionScene:
    """The scene of a station and block count, built once: reading and hulling the URDF meshes (~0.2 s) is most of
    a clearance check otherwise. Shared like ``load_ur3``'s models, so not thread-safe either."""
    return CollisionScene(station, n_blocks)



def resting_blocks(stacks: Sequence[Sequence[Sequence[int]]], moves: Sequence[Move], mi: int,
                    ph: Phase) -> dict[int, Slot]:
    """Block -> slot of every block at rest during phase ``ph`` of move ``mi`` (-1: before the first move, or on
    the way home): the carried block is not at rest; a just-placed block rests on its destination."""
    state = stacks[mi] if mi >= 0 else (stacks[-1] if ph == Phase.HOME else stacks[0])
    slots = {b: (t, h) for t, st in enumerate(state) for h, b in enumerate(st)}
    if mi < 0:
        return slots
    m = moves[mi]
    if ph in (Phase.RELEASE_DWELL, Phase.RETREAT):
        slots.pop(m.block, None)
        slots[m.block] = (m.to_tower, m.to_height)
    if ph.carrying:
        slots.pop(m.block, None)
    return slots


@dataclass(frozen=True)
class Rule:
    """Required clearances of one ``mover`` ("robot": every robot geometry but the base, "cup", or "carried")
    against each of ``blocks`` (resting blocks; None stands for the table), at least ``required_m`` [m] (0: strictly
    positive)."""

    mover: str
    blocks: tuple[int | None, ...]
    required_m: float


def clearance_rules(station: Station, ph: Phase, m: Move | None, slots: dict[int, Slot],
                    clearance_m: float) -> list[Rule]:
    """The clearances required during phase ``ph`` of move ``m`` (None: before the first move / on the way home)
    with the resting blocks ``slots`` (block -> slot).

    Robot geometry and cup vs the table and every resting block (> 0), except: the base (mounted on the table),
    the cup vs the table while at contact (vertical and dwell phases), the cup vs the block it picks or placed.
    While carrying: the carried block vs the table (> 0, while carrying across) and every resting block
    (>= ``clearance_m``), except the block it rests on at contact (stacked layout: the one under its source while
    lifting, under its destination while descending to place).
    """
    blocks = tuple(slots)
    cup_on = m.block if m is not None and ph in _CUP_ON_MOVED_BLOCK else None
    cup_table: tuple[int | None, ...] = () if ph in (*VERTICAL_PHASES, *DWELL_PHASES) else (None,)
    rules = [Rule("robot", (None, *blocks), 0.0),
             Rule("cup", (*cup_table, *(b for b in blocks if b != cup_on)), 0.0)]
    if m is None or not ph.carrying:
        return rules
    under = None
    if station.layout == "stacked":
        if ph == Phase.LIFT and m.from_height > 0:
            under = (m.from_tower, m.from_height - 1)
        if ph == Phase.DESCEND_PLACE and m.to_height > 0:
            under = (m.to_tower, m.to_height - 1)
    if ph == Phase.CARRY:
        rules.append(Rule("carried", (None,), 0.0))
    rules.append(Rule("carried", tuple(b for b, slot in slots.items() if slot != under), clearance_m))
    return rules


def _pairs(scene: CollisionScene, rules: Sequence[Rule]) -> list[Pair]:
    """The scene's geometry pairs of ``rules`` (a robot rule expands to every robot geometry but the base)."""
    pairs: list[Pair] = []
    for r in rules:
        for b in r.blocks:
            target = scene.table if b is None else scene.blocks[b]
            for g in scene.movers(r.mover):
                pairs.append(((g, target), r.required_m))
    return pairs


def _decimated_distances(scene: CollisionScene, tr: Trajectory, run: npt.NDArray[np.intp],
                         keys: list[tuple[int, int]], required: FloatArray, stride: int,
                         speed_bound: FloatArray) -> dict[int, FloatArray]:
    """Distances of ``keys`` at every ``stride``-th sample of ``run`` (and its last), and at every sample of a
    coarse interval whose margin does not prove the pairs clear in between (see :class:`CollisionScene`)."""
    coarse = list(run[::stride])
    if coarse[-1] != run[-1]:
        coarse.append(run[-1])
    d_coarse = {k: scene.distances(tr.q[k], keys) for k in coarse}
    checked: dict[int, FloatArray] = dict(d_coarse)
    for a, b in itertools.pairwise(coarse):
        vmax = np.max(speed_bound[a:b + 1], axis=0)
        delta = float(np.sum(vmax * scene.R)) * (tr.t[b] - tr.t[a]) / 2
        if np.any(np.minimum(d_coarse[a], d_coarse[b]) - required < delta):
            for k in range(a + 1, b):
                checked[k] = scene.distances(tr.q[k], keys)
    return checked


def check_collisions(tr: Trajectory, moves: Sequence[Move], station: Station, n_blocks: int, start: int,
                     config: PlanConfig, limits: KinematicLimits) -> list[str]:
    """Clearance checks of :class:`CollisionScene` on the sampled trajectory (at most ``MAX_REPORTED``)."""
    scene = _collision_scene(station, n_blocks)
    # Fresh GeometryData: Pinocchio warm-starts GJK from each pair's previous query (enable_cached_gjk_guess), so
    # reusing it would let the distances depend, in the last bits, on the plans checked before. Block placements
    # need no reset: every run below places all blocks before its first query.
    import pinocchio as pin

    scene.gd = pin.GeometryData(scene.gm)
    stacks = stacks_before_moves(moves, n_blocks, start, station.n_towers)
    out: list[str] = []
    dt = 1.0 / tr.rate_hz
    stride = max(1, round(tr.rate_hz / config.collision_rate_hz))
    speed_bound = np.abs(tr.qd) + limits.a_max * dt / 2  # bound between samples
    # Runs of constant (move, phase): the resting blocks and the checked pairs are fixed within each.
    change = np.flatnonzero((np.diff(tr.phase) != 0) | (np.diff(tr.move_index) != 0)) + 1
    for run in np.split(np.arange(len(tr.t)), change):
        mi, ph = int(tr.move_index[run[0]]), Phase(int(tr.phase[run[0]]))
        m = moves[mi] if mi >= 0 else None
        slots = resting_blocks(stacks, moves, mi, ph)
        scene.place_blocks(slots)
        pairs = _pairs(scene, clearance_rules(station, ph, m, slots, config.clearance_m))
        if not pairs:
            continue
        keys = [p for p, _ in pairs]
        req = np.array([r for _, r in pairs])
        checked = _decimated_distances(scene, tr, run, keys, req, stride, speed_bound)
        for k in sorted(checked):
            bad = np.flatnonzero(checked[k] < req + (req == 0) * 1e-9)
            for j in bad:
                g1, g2 = keys[j]
                out.append(f"{scene.name(g1)} is {checked[k][j] * 1e3:.2f} mm from {scene.name(g2)} (required "
                           f"{req[j] * 1e3:.1f} mm) at t = {tr.t[k]:.3f} s ({ph.name}, move {mi + 1})")
                break
            if len(out) >= MAX_REPORTED:
                return out
    return out
