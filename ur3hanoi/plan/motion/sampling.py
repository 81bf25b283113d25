"""Sampling of a plan: an exact, vectorised re-implementation of Ruckig's ``Trajectory.at_time``.

What it reproduces: for every sample ``t = i / rate_hz`` the state Ruckig's ``at_time`` returns for the segment
the sample falls in. Each DoF's Ruckig profile is 7 constant-jerk phases (``Profile.t`` durations; ``p``, ``v``,
``a`` at each phase start, and after the end); ``at_time`` finds the phase by upper_bound on the cumulative times
``t_sum`` and integrates the state from the phase start with ``ruckig::integrate``. :class:`_ProfileTable` does
the same lookup (with the same sequential sums) and the same arithmetic in the same order, for all samples of
the plan at once, so the samples equal ``at_time`` bit for bit (``tests/plan/motion/test_sampling.py`` compares them).
Vertical legs map the path coordinate (s, sd, sdd, sddd) to joints by the chain rule through the path's spline
(:class:`_StackedPaths`, the arithmetic of :meth:`VerticalPath.evaluate` for many paths at once).

Why: a per-sample Python loop over ``at_time`` cost ~25 ms per move; this costs a few hundredths of that, and the
per-segment Python work is reading each distinct Ruckig trajectory's profiles once. Segments whose profiles carry
a brake pre-profile (only for starts outside the limits, which the planner never produces) take the per-sample
``at_time`` path instead (:func:`_at_times`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
import numpy.typing as npt
from ruckig import Trajectory as RuckigTrajectory

from ur3hanoi.arrays import FloatArray
from ur3hanoi.plan.types import SUCTION_PHASES, Segment, Trajectory, VerticalPath
from ur3hanoi.robot.registry import N_JOINTS

_N_PIECES = 8  # pieces of a profile: 7 constant-jerk phases and the state after the end
# Samples per block of the elementwise evaluation. Arrays are joint-major (6, N), so broadcasting a per-sample (N,)
# operand runs numpy's inner loop over samples rather than over 6 joints; and blocks of 4096 keep every temporary
# (~200 kB) in cache and out of fresh-page allocation, ~3x faster than whole-plan temporaries.
_CHUNK = 4096


def _lexi_keys(group: npt.NDArray[np.intp], x: FloatArray) -> npt.NDArray[np.complex128]:
    """Keys that sort by (group, x) lexicographically: numpy orders complex numbers by real, then imaginary part.

    Used to run one exact ``searchsorted`` over many independently sorted runs (one run per group) at once.
    """
    return group.astype(float) + 1j * x


@dataclass(frozen=True)
class _ProfileTable:
    """Ruckig profiles of several trajectories, stacked as (trajectory row, DoF, piece) for vectorized evaluation.

    ``t_sum`` (R, D, 7): cumulative phase times (sequential sums, as Ruckig's own ``t_sum``, so the phase lookup
    matches it bit for bit); ``t0`` (R, D, 8): start time of each piece (0, then ``t_sum``); ``p, v, a, j``
    (R, D, 8): the state and jerk at each piece start. Piece 7 is "after the profile end" (constant acceleration,
    zero jerk), which Ruckig uses for a DoF that finishes early and at ``t = duration``.
    """

    t_sum: FloatArray
    t0: FloatArray
    p: FloatArray
    v: FloatArray
    a: FloatArray
    j: FloatArray

    @classmethod
    def of(cls, profiles: Sequence[Sequence[Any]]) -> _ProfileTable:
        """From ``profiles[r][d]`` (ruckig.Profile without brake), read once through the bindings as lists."""
        t = np.array([[prof.t for prof in row] for row in profiles], dtype=float).reshape(len(profiles), -1, 7)
        t_sum = np.cumsum(t, axis=2)  # add.accumulate: sequential, like Ruckig (not pairwise like np.sum)
        shape = (*t_sum.shape[:2], _N_PIECES)
        t0 = np.zeros(shape)
        t0[:, :, 1:] = t_sum
        p, v, a = (np.array([[getattr(prof, name) for prof in row] for row in profiles], dtype=float).reshape(shape)
                   for name in ("p", "v", "a"))
        j = np.zeros(shape)
        j[:, :, :7] = np.array([[prof.j for prof in row] for row in profiles], dtype=float).reshape((*shape[:2], 7))
        return cls(t_sum, t0, p, v, a, j)

    def evaluate(self, seg: npt.NDArray[np.intp], row_of_seg: npt.NDArray[np.intp], tau: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """(position, velocity, acceleration, jerk), each (D, N) (DoF-major), at local times ``tau`` (N,).

        ``seg`` (N,) is the sample's segment index, non-decreasing, with ``tau`` non-decreasing within a segment;
        ``row_of_seg`` maps a segment index to its table row (-1: not evaluated here).
        """
        D = self.p.shape[1]
        n = len(tau)
        segs = np.flatnonzero(row_of_seg >= 0)  # every segment of this table, sampled or not
        rows = row_of_seg[segs]
        # Phase lookup for all samples and DoFs: first sample at or after each (segment, phase end) by one
        # searchsorted on (segment, tau) keys; a sample's phase index is then the number of its segment's phase ends
        # at or before it (upper_bound, as Ruckig), i.e. a running count minus the 7 ends of every earlier segment.
        pos = np.searchsorted(_lexi_keys(seg, tau), _lexi_keys(np.repeat(segs, D * 7), self.t_sum[rows].ravel()),
                              side="left")
        # Each DoF counts into its own lane of n + 1 slots (pos is ordered segment, DoF, phase end).
        lanes = (np.arange(D)[:, None] * (n + 1) + pos.reshape(len(segs), D, 7)).ravel()
        marks = np.bincount(lanes, minlength=D * (n + 1)).reshape(D, n + 1)
        earlier = np.cumsum(row_of_seg >= 0) - 1  # rank of each segment among this table's segments
        piece = np.cumsum(marks[:, :n], axis=1) - 7 * earlier[seg]
        flat = (row_of_seg[seg] * D + np.arange(D)[:, None]) * _N_PIECES + piece
        out = np.empty((4, D, n))
        t0, p, v, a, j = (x.ravel() for x in (self.t0, self.p, self.v, self.a, self.j))
        for c in range(0, n, _CHUNK):
            f, tc = flat[:, c:c + _CHUNK], tau[c:c + _CHUNK]
            dt = tc - t0.take(f)  # ndarray.take: a faster gather than fancy indexing
            p0, v0, a0, jj = p.take(f), v.take(f), a.take(f), j.take(f)
            # ruckig::integrate, same operation order.
            out[0, :, c:c + _CHUNK] = p0 + dt * (v0 + dt * (a0 / 2 + dt * jj / 6))
            out[1, :, c:c + _CHUNK] = v0 + dt * (a0 + dt * jj / 2)
            out[2, :, c:c + _CHUNK] = a0 + dt * jj
            out[3, :, c:c + _CHUNK] = jj
        return out[0], out[1], out[2], out[3]


def _profile_jerk(traj: RuckigTrajectory, tau: FloatArray) -> FloatArray:
    """Jerk of a Ruckig trajectory at local times ``tau`` (N,), read from its own per-DoF profiles: (N, dofs)."""
    profiles = traj.profiles[0]
    out = np.zeros((len(tau), len(profiles)))
    for i, prof in enumerate(profiles):
        tb = float(prof.brake.duration)
        t_bounds = tb + np.cumsum(prof.t)
        idx = np.searchsorted(t_bounds, tau, side="right")
        jerks = np.append(np.asarray(prof.j, dtype=float), 0.0)  # after the end: constant velocity
        out[:, i] = jerks[np.minimum(idx, 7)]
        if tb > 0.0:  # a brake pre-profile
            bb = np.cumsum(prof.brake.t)
            in_brake = tau < tb
            bidx = np.minimum(np.searchsorted(bb, tau[in_brake], side="right"), 1)
            out[in_brake, i] = np.asarray(prof.brake.j, dtype=float)[bidx]
    return out


def _at_times(traj: RuckigTrajectory, tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Per-sample ``at_time`` (the fallback for profiles with a brake pre-profile): four (N, dofs) arrays."""
    states = np.array([traj.at_time(float(tt)) for tt in tau], dtype=float).reshape(len(tau), 3, -1)
    return states[:, 0], states[:, 1], states[:, 2], _profile_jerk(traj, tau)


def evaluate(traj: RuckigTrajectory, tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """(position, velocity, acceleration), each (N, dofs), of one Ruckig trajectory at local times ``tau`` (N,)
    [s], non-decreasing and within [0, duration]: the vectorised ``at_time`` (same arithmetic, see above).

    Used by the approach legs to check the vertical line densely (1 kHz) without a per-sample binding call.
    """
    profs = traj.profiles[0]
    if any(prof.brake.duration > 0.0 for prof in profs):
        x, xd, xdd, _ = _at_times(traj, tau)
        return x, xd, xdd
    n = len(tau)
    q, qd, qdd, _ = _ProfileTable.of([profs]).evaluate(np.zeros(n, dtype=np.intp), np.zeros(1, dtype=np.intp),
                                                       np.asarray(tau, dtype=float))
    return q.T, qd.T, qdd.T


class _StackedPaths:
    """The nodes of several :class:`VerticalPath` stacked (joint-major), to evaluate many paths in one call."""

    def __init__(self, paths: Sequence[VerticalPath]) -> None:
        self.sizes = np.array([len(vp.s) for vp in paths])
        self.first = np.cumsum(self.sizes) - self.sizes  # index of each path's first node
        self.s = np.concatenate([vp.s for vp in paths])
        self.q, self.dq, self.ddq, self.dddq = (np.concatenate([getattr(vp, name) for vp in paths]).T.copy()
                                                for name in ("q", "dq", "ddq", "dddq"))
        self.length = np.array([vp.length_m for vp in paths])
        self.node_keys = _lexi_keys(np.repeat(np.arange(len(paths)), self.sizes), self.s)

    def evaluate(self, which: npt.NDArray[np.intp], s: FloatArray
                 ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`VerticalPath.evaluate` of path ``which[i]`` at ``s[i]`` (same arithmetic): four (6, N) arrays.

        One searchsorted on (path, s) keys finds each sample's node interval in its own path.
        """
        S = self.s
        s = np.minimum(np.maximum(s, 0.0), self.length[which])
        k = np.minimum(np.searchsorted(self.node_keys, _lexi_keys(which, s), side="right") - 1,
                       self.first[which] + self.sizes[which] - 2)
        k1 = k + 1
        h = S.take(k1) - S.take(k)
        u = (s - S.take(k)) / h
        # ndarray.take(axis=1): ~2x faster than fancy indexing [:, k] for these gathers.
        q0, q1, m0, m1 = self.q.take(k, 1), self.q.take(k1, 1), self.dq.take(k, 1) * h, self.dq.take(k1, 1) * h
        u2, u3 = u * u, u * u * u
        q = (2 * u3 - 3 * u2 + 1) * q0 + (u3 - 2 * u2 + u) * m0 + (-2 * u3 + 3 * u2) * q1 + (u3 - u2) * m1
        dq = ((6 * u2 - 6 * u) * q0 + (3 * u2 - 4 * u + 1) * m0 + (-6 * u2 + 6 * u) * q1 + (3 * u2 - 2 * u) * m1) / h
        ddq = (1 - u) * self.ddq.take(k, 1) + u * self.ddq.take(k1, 1)
        dddq = (1 - u) * self.dddq.take(k, 1) + u * self.dddq.take(k1, 1)
        return q, dq, ddq, dddq


# Stacked nodes per set of paths (by identity; the entry holds the paths, so their ids are not reused while cached).
# The paths come from the per-station waypoint cache, so repeated plans on a station reuse the same stacks.
_STACKED_CACHE: dict[tuple[int, ...], tuple[tuple[VerticalPath, ...], _StackedPaths]] = {}


def _stacked_paths(paths: Sequence[VerticalPath]) -> _StackedPaths:
    key = tuple(id(vp) for vp in paths)
    hit = _STACKED_CACHE.get(key)
    if hit is None:
        if len(_STACKED_CACHE) >= 64:
            _STACKED_CACHE.clear()
        hit = _STACKED_CACHE[key] = (tuple(paths), _StackedPaths(paths))
    return hit[1]


class _SegmentRows(NamedTuple):
    """Where each segment's samples come from: a row of the joint (0) or path (1) profile table (-1: none), its
    vertical path, its rest pose (a dwell), or a per-sample evaluation (``slow``: a brake pre-profile)."""

    row_of_seg: npt.NDArray[np.intp]  # (2, n_seg)
    profiles: tuple[list[Any], list[Any]]  # joint, path: the profiles of each distinct trajectory
    path_of_seg: npt.NDArray[np.intp]  # (n_seg,) index into paths
    paths: list[VerticalPath]
    dwell_q: FloatArray  # (6, n_seg) [rad]
    slow: list[int]


def _segment_rows(segments: Sequence[Segment]) -> _SegmentRows:
    """The table rows of every segment. The builder reuses one Ruckig trajectory for repeated legs, so each
    distinct trajectory (by identity) is read from the bindings once."""
    n_seg = len(segments)
    rows: tuple[dict[int, int], dict[int, int]] = ({}, {})  # joint, path: id(trajectory) -> row
    profiles: tuple[list[Any], list[Any]] = ([], [])
    row_of_seg = np.full((2, n_seg), -1, dtype=np.intp)
    path_rows: dict[int, int] = {}
    path_list: list[VerticalPath] = []
    path_of_seg = np.zeros(n_seg, dtype=np.intp)
    dwell_q = np.zeros((N_JOINTS, n_seg))
    slow: list[int] = []
    for k, seg in enumerate(segments):
        traj = seg.trajectory
        if traj is None:
            dwell_q[:, k] = seg.q_start
            continue
        kind = 0 if seg.path is None else 1
        r = rows[kind].get(id(traj))
        if r is None:
            profs = traj.profiles[0]
            if any(prof.brake.duration > 0.0 for prof in profs):
                slow.append(k)
                continue
            r = rows[kind][id(traj)] = len(profiles[kind])
            profiles[kind].append(profs)
        row_of_seg[kind, k] = r
        if seg.path is not None:
            path_of_seg[k] = path_rows.setdefault(id(seg.path), len(path_list))
            if path_of_seg[k] == len(path_list):
                path_list.append(seg.path)
    return _SegmentRows(row_of_seg, profiles, path_of_seg, path_list, dwell_q, slow)


def sample(segments: Sequence[Segment], rate_hz: float) -> Trajectory:
    """Uniform samples ``t = i / rate_hz`` of the chained segments, with suction, move index and phase.

    Joint segments: q, qd, qdd, qddd from the Ruckig profiles. Vertical legs: s, sd, sdd, sddd from the path
    trajectory's profile, mapped to joints by the chain rule. Both are evaluated for all samples at once (see the
    module docstring); the per-segment Python work is reading each distinct Ruckig trajectory's profiles once.
    """
    duration = segments[-1].t_end
    n = math.ceil(duration * rate_hz - 1e-9) + 1
    t = np.arange(n) / rate_hz
    starts = np.array([s.t_start for s in segments])
    durations = np.array([s.duration for s in segments])
    # searchsorted <= n_seg, so only the lower bound needs clamping (np.clip has a much larger fixed cost).
    seg_of = np.maximum(np.searchsorted(starts, t, side="right") - 1, 0)
    tau = np.minimum(t - starts[seg_of], durations[seg_of])
    seg_phase = np.array([int(s.phase) for s in segments], dtype=int)
    phase = seg_phase[seg_of]
    mi = np.array([s.move_index for s in segments], dtype=int)[seg_of]

    rows = _segment_rows(segments)
    row_of_seg, profiles, path_of_seg = rows.row_of_seg, rows.profiles, rows.path_of_seg

    # Joint-major (6, N) work arrays (see _ProfileTable.evaluate), transposed to the contract's (N, 6) at the end.
    q = rows.dwell_q[:, seg_of]  # the dwells' rest pose; moving samples are overwritten below
    qd, qdd, qddd = np.zeros((N_JOINTS, n)), np.zeros((N_JOINTS, n)), np.zeros((N_JOINTS, n))
    idx = np.flatnonzero(row_of_seg[0, seg_of] >= 0)
    if idx.size:
        q[:, idx], qd[:, idx], qdd[:, idx], qddd[:, idx] = _ProfileTable.of(profiles[0]).evaluate(
            seg_of[idx], row_of_seg[0], tau[idx])
    idx = np.flatnonzero(row_of_seg[1, seg_of] >= 0)
    if idx.size:
        s_all = _ProfileTable.of(profiles[1]).evaluate(seg_of[idx], row_of_seg[1], tau[idx])
        stacked = _stacked_paths(rows.paths)
        which = path_of_seg[seg_of[idx]]
        for c in range(0, len(idx), _CHUNK):
            ii, cc = idx[c:c + _CHUNK], slice(c, c + _CHUNK)
            s, sd, sdd, sddd = (x[0, cc] for x in s_all)
            q[:, ii], d1, d2, d3 = stacked.evaluate(which[cc], s)
            qd[:, ii] = d1 * sd
            qdd[:, ii] = d2 * sd * sd + d1 * sdd
            qddd[:, ii] = d3 * sd**3 + 3 * d2 * sd * sdd + d1 * sddd
    for k in rows.slow:
        seg = segments[k]
        assert seg.trajectory is not None
        i0, i1 = np.searchsorted(seg_of, [k, k + 1])
        x, xd, xdd, xddd = _at_times(seg.trajectory, tau[i0:i1])
        if seg.path is None:
            q[:, i0:i1], qd[:, i0:i1], qdd[:, i0:i1], qddd[:, i0:i1] = x.T, xd.T, xdd.T, xddd.T
        else:
            x, xd, xdd, xddd = x[:, 0], xd[:, 0], xdd[:, 0], xddd[:, 0]
            q[:, i0:i1], d1, d2, d3 = (y.T for y in seg.path.evaluate_many(x))
            qd[:, i0:i1] = d1 * xd
            qdd[:, i0:i1] = d2 * xd * xd + d1 * xdd
            qddd[:, i0:i1] = d3 * xd**3 + 3 * d2 * xd * xdd + d1 * xddd
    # Samples after the end (the last one) hold the final state at rest.
    last = t > duration
    qd[:, last], qdd[:, last], qddd[:, last] = 0.0, 0.0, 0.0
    # Per segment then gathered (np.isin has a large fixed cost, ~0.1 ms, against a few us for this).
    suction = np.array([seg.phase in SUCTION_PHASES for seg in segments], dtype=bool)[seg_of]
    q, qd, qdd, qddd = (np.ascontiguousarray(x.T) for x in (q, qd, qdd, qddd))
    return Trajectory(rate_hz=float(rate_hz), t=t, q=q, qd=qd, qdd=qdd, qddd=qddd, suction=suction,
                      move_index=mi, phase=phase)

