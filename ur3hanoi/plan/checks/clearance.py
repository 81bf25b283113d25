"""Clearance checks of a plan's segments, once per distinct segment: the check the planner runs.

The planner reuses one Ruckig trajectory for every repetition of a leg or a motion across, so the distances of a
segment's moving geometry (robot, cup, carried block) to every slot a block can rest in depend on the segment
alone. :class:`SegmentClearance` computes them in the segment's own time, on demand per (mover, slot), and keeps
them; :func:`check_segments` applies the rules of :func:`~ur3hanoi.plan.checks.collision.clearance_rules` to each
segment of a plan with the blocks resting at that moment. A long solve checks each distinct motion once instead of
every sample of every move.

Guarantee (continuous time, resolved to 1 ms): the segment is cut at ``1 / collision_rate_hz`` and at its end.
Between two cuts no point of the moving geometry is farther than ``delta = sum_i vb_i R_i (t_b - t_a) / 2`` from
its position at the nearer cut (``vb_i`` bounds joint i's speed in between: the larger end speed plus
``a_max dt / 2``; ``R_i`` as in :class:`~ur3hanoi.plan.checks.collision.CollisionScene`). A pair is proven clear on an
interval when its distance at both cuts exceeds the requirement by ``delta``: first with bounding spheres against the
block box (a few numpy operations for every slot at once), then with the exact coal distance, and otherwise the
interval is halved until it is proven or 1 ms long (where the distances at its ends decide, as a 1 kHz check
would). GJK starts from its default guess, so every distance is independent of the queries before it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from functools import lru_cache

import coal
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.hanoi import Move, stacks_before_moves
from ur3hanoi.plan.checks.collision import MAX_REPORTED, CollisionScene, clearance_rules, resting_blocks
from ur3hanoi.plan.motion.sampling import evaluate
from ur3hanoi.plan.motion.waypoints import geometry_key
from ur3hanoi.plan.types import KinematicLimits, Phase, PlanConfig, Segment
from ur3hanoi.robot.dh import dh_frames, dh_link
from ur3hanoi.robot.model import T_BASELINK_BASE
from ur3hanoi.robot.registry import N_JOINTS
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import block_center_world, table_z

Slot = tuple[int, int]
FINEST_S = 1e-3  # [s] intervals are not halved below this: 1 kHz resolution
STRICT_M = 1e-9  # [m] a "> 0" requirement means at least this


@dataclass(frozen=True)
class Result:
    """Worst distance [m] of a mover to a target over a segment, where (local time [s]), by which geometry, and
    whether the requirement holds over the whole segment."""

    ok: bool
    distance_m: float
    t_s: float
    geometry: int


@dataclass
class _Status:
    """Per target of one (mover, requirement) on one segment: result known yet, and clear."""

    known: npt.NDArray[np.bool_]
    ok: npt.NDArray[np.bool_]


class _Scene:
    """The collision scene with one probe block (moved to any slot) and bounding spheres of every geometry."""

    def __init__(self, station: Station) -> None:
        self.station = station
        self.cs = CollisionScene(station, 1)
        self.probe = self.cs.blocks[0]
        gm = self.cs.gm
        self.model, self.data = self.cs.model, self.cs.data
        self.movers = {k: self.cs.movers(k) for k in ("robot", "cup", "carried")}
        geoms = sorted({g for v in self.movers.values() for g in v})
        self.geoms = geoms
        self.index = {g: i for i, g in enumerate(geoms)}
        self.parent = np.array([gm.geometryObjects[g].parentJoint for g in geoms])
        centers, radii = [], []
        for g in geoms:
            obj = gm.geometryObjects[g]
            obj.geometry.computeLocalAABB()
            centers.append(obj.placement.act(np.asarray(obj.geometry.aabb_center, dtype=float)))
            radii.append(float(obj.geometry.aabb_radius))
        self.centers = np.array(centers)  # in the parent joint frame
        self.radii = np.array(radii)
        # Targets in base_link (the model's universe): every slot's block box, then the table.
        T = self.cs.T_baselink_world
        R_block = T.rotation @ self.cs._R_block
        s = station.block_size
        self.slots: list[Slot] = [(t, h) for t in range(station.n_towers) for h in range(station.n_heights)]
        self.slot_index = {sl: i for i, sl in enumerate(self.slots)}
        box_c = [T.act(block_center_world(station, *sl)) for sl in self.slots]
        box_c.append(T.act(np.array([0.0, 0.0, table_z(station) - 0.05])))
        self.box_c = np.array(box_c)
        self.box_R = np.array([R_block] * len(self.slots) + [T.rotation])
        self.box_h = np.array([[s / 2] * 3] * len(self.slots) + [[2.0, 2.0, 0.05]])
        self.block_placement = [T * pin.SE3(self.cs._R_block, block_center_world(station, *sl)) for sl in self.slots]
        # Each joint's placement relative to its DH frame (both are fixed to the same link): constant.
        q0 = np.zeros(N_JOINTS)
        pin.forwardKinematics(self.model, self.data, q0)
        T = T_BASELINK_BASE.homogeneous
        self.dh_to_joint = []
        for i in range(N_JOINTS):
            T = T @ dh_link(0.0, i, station.robot.dh)
            self.dh_to_joint.append(np.linalg.inv(T) @ self.data.oMi[i + 1].homogeneous)
        self.gd = pin.GeometryData(gm)
        for req in self.gd.distanceRequests:  # explicit: never warm-start GJK from a previous query
            req.gjk_initial_guess = coal.GJKInitialGuess.DefaultGuess

    def joint_frames(self, q: FloatArray) -> FloatArray:
        """(S, njoints, 4, 4) placements of the model's joints in base_link at the configurations ``q`` (S, 6): the
        DH chain (batched) times each joint's constant offset from its DH frame, i.e. Pinocchio's ``oMi``."""
        out = np.empty((len(q), self.model.njoints, 4, 4))
        out[:, 0] = np.eye(4)
        for i, T in enumerate(dh_frames(q, self.station.robot.dh, T_BASELINK_BASE.homogeneous)):
            out[:, i + 1] = T @ self.dh_to_joint[i]
        return out

    def sphere_bounds(self, q: FloatArray) -> FloatArray:
        """Lower bounds (S, G, targets) [m] of the distance from each geometry's bounding sphere to each target
        box, at the configurations ``q`` (S, 6)."""
        F = self.joint_frames(q)[:, self.parent]  # (S, G, 4, 4)
        c = np.einsum("sgij,gj->sgi", F[:, :, :3, :3], self.centers) + F[:, :, :3, 3]  # (S, G, 3)
        local = np.einsum("bji,sgbj->sgbi", self.box_R, c[:, :, None, :] - self.box_c[None, None])
        out = np.linalg.norm(np.maximum(np.abs(local) - self.box_h, 0.0), axis=-1)
        return out - self.radii[None, :, None]

    def distances(self, q: FloatArray, geoms: Sequence[int], target: int) -> FloatArray:
        """Exact distances [m] of ``geoms`` to target ``target`` (a slot index, or len(slots): the table)."""
        gm = self.cs.gm
        if target < len(self.slots):
            gm.geometryObjects[self.probe].placement = self.block_placement[target]
            other = self.probe
        else:
            other = self.cs.table
        pin.updateGeometryPlacements(self.model, self.data, gm, self.gd, q)
        return np.array([pin.computeDistance(gm, self.gd, self.cs.pairs[(g, other)]).min_distance for g in geoms])


@lru_cache(maxsize=8)
def _scene(station: Station) -> _Scene:
    return _Scene(station)


@dataclass
class SegmentClearance:
    """The clearances of one distinct segment's motion, computed on demand per (mover, target) and kept.

    ``motion(t)`` returns (q [rad], qd [rad/s]) at local times ``t`` (N,) [s]; a dwell has duration 0.
    """

    scene: _Scene
    duration: float
    motion: Callable[[FloatArray], tuple[FloatArray, FloatArray]]
    a_max: FloatArray
    step_s: float
    results: dict[tuple[str, int, float], Result] = field(default_factory=dict)
    status: dict[tuple[str, float], _Status] = field(default_factory=dict)

    def __post_init__(self) -> None:
        n = max(1, math.ceil(self.duration / self.step_s - 1e-9))
        self.t = np.minimum(np.arange(n + 1) * self.step_s, self.duration) if self.duration > 0 else np.zeros(1)
        self.q, self.qd = self.motion(self.t)
        self.bounds = self.scene.sphere_bounds(self.q)
        dt = np.diff(self.t)
        vb = np.maximum(np.abs(self.qd[:-1]), np.abs(self.qd[1:])) + self.a_max * dt[:, None] / 2
        self.deltas = (vb @ self.scene.cs.R) * dt / 2  # (S - 1,) [m]: displacement bound of each interval

    def _status(self, mover: str, required: float) -> _Status:
        """Per target: proven clear by the bounds alone over the whole segment (one vectorised test)."""
        key = (mover, required)
        if key not in self.status:
            cols = [self.scene.index[g] for g in self.scene.movers[mover]]
            lbs = np.min(self.bounds[:, cols, :], axis=1)  # (S, targets)
            need = max(required, STRICT_M)
            if len(self.t) == 1:
                proven = np.zeros(lbs.shape[1], dtype=bool)
            else:
                proven = np.all(np.minimum(lbs[:-1], lbs[1:]) - need >= self.deltas[:, None], axis=0)
            self.status[key] = _Status(proven.copy(), proven.copy())
        return self.status[key]

    def failures(self, mover: str, required: float, targets: npt.NDArray[np.intp]) -> list[tuple[int, Result]]:
        """(target, result) of each of ``targets`` (indices) the mover does not clear by ``required`` [m]."""
        st = self._status(mover, required)
        for k in targets[~st.known[targets]].tolist():
            r = self._check(mover, k, required)
            st.known[k], st.ok[k] = True, r.ok
            self.results[(mover, k, required)] = r
        return [(k, self.results[(mover, k, required)]) for k in targets[~st.ok[targets]].tolist()]

    def _check(self, mover: str, target: int, required: float) -> Result:
        sc = self.scene
        geoms = sc.movers[mover]
        cols = [sc.index[g] for g in geoms]
        need = max(required, STRICT_M)
        worst = [math.inf, 0.0, geoms[0]]
        exact: dict[float, float] = {}

        def exact_at(t: float, q: FloatArray) -> float:
            if t not in exact:
                d = sc.distances(q, geoms, target)
                i = int(np.argmin(d))
                exact[t] = float(d[i])
                if d[i] < worst[0]:
                    worst[:] = [float(d[i]), t, geoms[i]]
            return exact[t]

        R = sc.cs.R.tolist()
        a_max = self.a_max.tolist()

        def delta(qd_a: FloatArray, qd_b: FloatArray, dt: float) -> float:
            return sum((max(abs(x), abs(y)) + a * dt / 2) * r
                       for x, y, a, r in zip(qd_a.tolist(), qd_b.tolist(), a_max, R, strict=True)) * dt / 2

        def interval(ta: float, tb: float, qa: FloatArray, qb: FloatArray, qda: FloatArray, qdb: FloatArray,
                     la: float, lb: float) -> None:
            d = delta(qda, qdb, tb - ta)
            if min(la, lb) - need >= d:
                return
            la, lb = exact_at(ta, qa), exact_at(tb, qb)
            if min(la, lb) - need >= d or tb - ta <= FINEST_S:
                return
            tm = 0.5 * (ta + tb)
            qm, qdm = (x[0] for x in self.motion(np.array([tm])))
            lm = float(np.min(sc.sphere_bounds(qm[None])[0, cols, target]))
            interval(ta, tm, qa, qm, qda, qdm, la, lm)
            interval(tm, tb, qm, qb, qdm, qdb, lm, lb)

        lbs = np.min(self.bounds[:, cols, target], axis=1)
        if len(self.t) == 1:
            exact_at(0.0, self.q[0])
        # Intervals the sphere bounds prove clear are skipped without a Python step.
        for k in np.flatnonzero(np.minimum(lbs[:-1], lbs[1:]) - need < self.deltas).tolist():
            interval(float(self.t[k]), float(self.t[k + 1]), self.q[k], self.q[k + 1], self.qd[k], self.qd[k + 1],
                     float(lbs[k]), float(lbs[k + 1]))
        if not exact:  # proven by the bounds everywhere: report the smallest bound
            k = int(np.argmin(lbs))
            return Result(True, float(lbs[k]), float(self.t[k]), geoms[0])
        return Result(worst[0] >= need, worst[0], worst[1], int(worst[2]))


class ClearanceCache:
    """The :class:`SegmentClearance` of every distinct segment of a station (by trajectory identity; entries keep
    their trajectory, so an identity is never reused while cached)."""

    def __init__(self, station: Station, limits: KinematicLimits, step_s: float) -> None:
        self.scene = _scene(geometry_key(station))
        self.limits = limits
        self.step_s = step_s
        self.entries: dict[tuple[int, int, bytes], tuple[object, SegmentClearance]] = {}

    def of(self, seg: Segment) -> SegmentClearance:
        traj = seg.trajectory
        key = (id(traj), id(seg.path), seg.q_start.tobytes() if traj is None else b"")
        hit = self.entries.get(key)
        if hit is None:
            hit = (traj, SegmentClearance(self.scene, seg.duration if traj is not None else 0.0, _motion(seg),
                                          self.limits.a_max, self.step_s))
            self.entries[key] = hit
        return hit[1]


def _motion(seg: Segment) -> Callable[[FloatArray], tuple[FloatArray, FloatArray]]:
    """(q, qd) of a segment at local times: the Ruckig trajectory (through the path for an exact vertical leg)."""
    traj = seg.trajectory
    if traj is None:
        q0 = seg.q_start
        return lambda t: (np.broadcast_to(q0, (len(t), N_JOINTS)).copy(), np.zeros((len(t), N_JOINTS)))
    path = seg.path
    if path is None:
        return lambda t: evaluate(traj, t)[:2]

    def along(t: FloatArray) -> tuple[FloatArray, FloatArray]:
        s, sd, _ = evaluate(traj, t)
        q, d1, _, _ = path.evaluate_many(s[:, 0])
        return q, d1 * sd

    return along


@lru_cache(maxsize=16)
def clearance_cache(station: Station, limits_key: tuple[tuple[float, ...], ...], step_s: float) -> ClearanceCache:
    """The cached :class:`ClearanceCache` of a station and planning limits (``limits_key``: v, a, j tuples)."""
    v, a, j = (np.array(x) for x in limits_key)
    return ClearanceCache(station, KinematicLimits(v, a, j), step_s)


def check_segments(segments: Sequence[Segment], moves: Sequence[Move], station: Station, n_blocks: int, start: int,
                   config: PlanConfig, limits: KinematicLimits) -> list[str]:
    """Clearance violations of a plan's segments (at most ``MAX_REPORTED``), with the blocks at rest at each."""
    key = (tuple(limits.v_max.tolist()), tuple(limits.a_max.tolist()), tuple(limits.j_max.tolist()))
    cache = clearance_cache(geometry_key(station), key, 1.0 / config.collision_rate_hz)
    sc = cache.scene
    stacks = stacks_before_moves(moves, n_blocks, start, station.n_towers)
    table = len(sc.slots)
    out: list[str] = []
    groups_memo: dict[tuple[int, int], list[tuple[str, float, npt.NDArray[np.intp], tuple[int | None, ...]]]] = {}
    for seg in segments:
        mi, ph = seg.move_index, seg.phase
        if (mi, int(ph)) not in groups_memo:
            slots = resting_blocks(stacks, moves, mi, ph)
            index = {b: sc.slot_index[s] for b, s in slots.items()}
            groups_memo[(mi, int(ph))] = [
                (r.mover, r.required_m, np.array([table if b is None else index[b] for b in r.blocks], dtype=np.intp),
                 r.blocks)
                for r in clearance_rules(station, ph, moves[mi] if mi >= 0 else None, slots, config.clearance_m)
                if r.blocks]
        entry = cache.of(seg)
        for mover, required, target_ix, blocks in groups_memo[(mi, int(ph))]:
            for k, res in entry.failures(mover, required, target_ix):
                block = blocks[target_ix.tolist().index(k)]
                other = "table" if block is None else f"block_{block}"
                out.append(f"{sc.cs.name(res.geometry)} is {res.distance_m * 1e3:.2f} mm from {other} (required "
                           f"{required * 1e3:.1f} mm) at t = {seg.t_start + res.t_s:.3f} s ({Phase(ph).name}, "
                           f"move {mi + 1})")
                if len(out) >= MAX_REPORTED:
                    return out
    return out
