"""Synthetic stations that look like the 27 real UR3 stations of issue 37, and their taught files (seeded).

What the real stations showed (hand-recorded lab tables, not in this repository): each tower's bottom contact stands
12.6-104.6 mm (median 50 mm) from where ``lab_real``'s layout, moved and turned as a whole onto the other two
towers, puts it; on some stations every contact of one tower is tilted 6.2-6.3 deg from the others' (the student
held the wrist differently there, consistently); recording noise is 1-3 mm, with an occasional contact about 10 mm
off its grid place. So a station here (:func:`station`) is ``lab_real``'s layout turned by up to
:data:`TURN_DEG` and moved by up to :data:`SHIFT_MM` as a whole, then each tower moved on its own by 0 to
:data:`TOWER_MM` (110 mm) in a random horizontal direction, kept distinct (:data:`MIN_APART_MM` apart) and in reach.
Its poses (:func:`recorded`): one tower tilted :data:`TILT_DEG` (6-7 deg) on every point, about a random horizontal
axis; every suction point moved 1-3 mm in a random direction; with probability :data:`ODD_P` one contact moved
:data:`ODD_MM` (10 mm) sideways (a contact's height is set by the block the cup is pressed on, its place by the
student's eye); above poses at the station's approach, 15-60 mm over their contact (each with the same noise).

Files (:func:`files`): three bottom contacts (one per tower), the taught example's pattern, teach's required poses
(the start tower's top, the others' bottom), and the full lab table's nine contacts. A lab table
(:func:`lab_table`) has them with one above pose per tower, over the top of the stack, shared by its heights (as
students record it: the carry height clears a full stack).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from tests.support import gross_matrix as gm
from tests.support import recorded_tables as rt
from ur3hanoi.calibrate import fit_station
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.errors import TaughtPointsError
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, ON, contact_point_world

Slot = tuple[int, int, int]
TURN_DEG = 15.0
SHIFT_MM = 30.0
TOWER_MM = 110.0
MIN_APART_MM = 80.0
"""[mm] towers at least this far apart (a block is 31.8 mm; real towers stand 110-150 mm apart)."""
TILT_DEG = (6.0, 7.0)
NOISE_MM = (1.0, 3.0)
ODD_MM = 10.0
ODD_P = 0.3
APPROACH_MM = (15.0, 60.0)


@dataclass(frozen=True)
class RealLike:
    """A real-like station: its grid (``truth``), the tower tilted on every point, and its recorded poses
    ``q`` (T, H, 2, 6) [rad] with the one odd contact (None when none)."""

    seed: int
    truth: Station
    tilted: int
    q: np.ndarray
    odd: Slot | None

    @property
    def name(self) -> str:
        return f"real-like {self.seed}"


def station(rng: np.random.Generator, base: Station) -> Station:
    """``base``'s layout turned and moved as a whole, each tower moved on its own (see the module docstring)."""
    o = np.asarray(base.tower_origins, dtype=float)
    for _ in range(200):
        a = math.radians(float(rng.uniform(-TURN_DEG, TURN_DEG)))
        R = np.array([[math.cos(a), -math.sin(a), 0.0], [math.sin(a), math.cos(a), 0.0], [0.0, 0.0, 1.0]])
        shift = np.append(rng.uniform(-SHIFT_MM, SHIFT_MM, 2), 0.0) * 1e-3
        own = rng.uniform(0.0, TOWER_MM, len(o))[:, None] * np.array(
            [[math.cos(b), math.sin(b), 0.0] for b in rng.uniform(-math.pi, math.pi, len(o))]) * 1e-3
        moved = (o - o.mean(axis=0)) @ R.T + o.mean(axis=0) + shift + own
        apart = min(float(np.hypot(*(moved[i, :2] - moved[j, :2]))) for i in range(len(o)) for j in range(i))
        if apart * 1e3 < MIN_APART_MM:
            continue
        try:
            return base.with_grid(moved, R @ np.asarray(base.height_step), base.tool_yaw)
        except Exception:  # out of reach: draw again
            continue
    raise RuntimeError("no station in reach")


def recorded(truth: Station, rng: np.random.Generator, tilted: int, tilt_deg: float, tilt_about: float,
             odd: Slot | None) -> np.ndarray:
    """Every pose (T, H, 2, 6) [rad] as a student records them (see the module docstring)."""
    q = np.empty((truth.n_towers, truth.n_heights, 2, 6))
    approach = float(rng.uniform(*APPROACH_MM)) * 1e-3
    for t in range(truth.n_towers):
        R = rt.R_tcp(truth.tool_yaw, tilt_deg if t == tilted else 0.0, tilt_about)
        for h in range(truth.n_heights):
            for k in (ON, ABOVE):
                p = contact_point_world(truth, t, h).copy()
                if k == ABOVE:
                    p[2] += approach
                v = rng.normal(size=3)
                p += v / np.linalg.norm(v) * float(rng.uniform(*NOISE_MM)) * 1e-3
                if (t, h, k) == odd:
                    b = float(rng.uniform(-math.pi, math.pi))
                    p += np.array([math.cos(b), math.sin(b), 0.0]) * ODD_MM * 1e-3
                q[t, h, k] = rt.pose_q(truth, p, R)
    return q


def real_like(seed: int, base: Station | None = None) -> RealLike:
    """The seeded real-like station ``seed`` on ``base`` (default ``lab_real``)."""
    base = base or load_station("lab_real")
    rng = np.random.default_rng(1000 + seed)
    for _ in range(50):
        truth = station(rng, base)
        tilted = int(rng.integers(truth.n_towers))
        tilt, about = float(rng.uniform(*TILT_DEG)), float(rng.uniform(-math.pi, math.pi))
        odd = ((int(rng.integers(truth.n_towers)), int(rng.integers(truth.n_heights)), ON) if rng.uniform() < ODD_P
               else None)
        try:
            return RealLike(seed, truth, tilted, recorded(truth, rng, tilted, tilt, about, odd), odd)
        except ValueError:  # a pose out of reach on the home's branch: draw again
            continue
    raise RuntimeError(f"no real-like station in reach for seed {seed}")


def files(base: Station) -> dict[str, list[Slot]]:
    """The taught files of a student (see the module docstring); ``teach`` names the start tower's top first."""
    n_t, n_h = base.n_towers, base.n_heights
    return {"bottom": [(t, 0, ON) for t in range(n_t)],
            "example": [(0, 0, ON), (1, 0, ON), (2, 0, ON), (0, 2, ON), (2, 1, ABOVE)],
            "teach": [(0, n_h - 1, ON), *((t, 0, ON) for t in range(1, n_t))],
            "table": [(t, h, ON) for t in range(n_t) for h in range(n_h)]}


def lab_table(st: RealLike, rng: np.random.Generator) -> np.ndarray:
    """The station's poses as a lab table (T, H, 2, 6) [rad]: its contacts, and per tower one above pose 15-60 mm
    over the top of its stack (1-3 mm of noise), the same for every height."""
    q, truth = st.q.copy(), st.truth
    over = float(rng.uniform(*APPROACH_MM)) * 1e-3
    for t in range(truth.n_towers):
        p = contact_point_world(truth, t, truth.n_heights - 1) + np.array([0.0, 0.0, over])
        v = rng.normal(size=3)
        p += v / np.linalg.norm(v) * float(rng.uniform(*NOISE_MM)) * 1e-3
        q[t, :, ABOVE] = rt.pose_q(truth, p, rt.R_tcp(truth.tool_yaw))
    return q


def taught(q: np.ndarray, slots: list[Slot], wrong: int = -1, q_wrong: np.ndarray | None = None) -> TaughtPoints:
    """The points of ``slots`` from the recorded poses ``q``, point ``wrong`` replaced by ``q_wrong``."""
    points = tuple(TaughtPoint(index=i, tower=s[0], height=s[1], k=s[2],
                               q=tuple(float(v) for v in (q_wrong if i == wrong and q_wrong is not None else q[s])))
                   for i, s in enumerate(slots))
    return TaughtPoints(points=points, source="t.yaml", sha256="")


def gross_cases(st: RealLike, base: Station, names: tuple[str, ...] = ("bottom", "example", "teach", "table"),
                every: int = 1) -> list[gm.Case]:
    """Every slot of the files ``names`` with every error of :data:`tests.support.gross_matrix.KINDS` (``every``
    > 1: one error per slot, taking turns), injected as in issue 33's matrix into the real-like poses."""
    truth = gm.Truth(st.name, base, st.truth)
    out = []
    rng = np.random.default_rng(st.seed)
    chosen = files(base)
    for name in names:
        slots = chosen[name]
        for i, slot in enumerate(slots):
            for n, kind in enumerate(gm.KINDS):
                qi = gm.inject(kind, st.q, truth, slot, rng)
                if every > 1 and (n + i) % every:
                    continue
                out.append(gm.Case(truth, name, tuple(slots), i, kind, taught(st.q, slots, i, qi)))
    return out


def outcome(case: gm.Case) -> tuple[str, str]:
    """:func:`tests.support.gross_matrix.outcome` of a real-like case: a point named and left out must leave every
    tower within 3 mm plus the recording noise of where the calibration of the good points alone puts it (the robust
    fit may leave out a noisy good point with the wrong one), one kept within the always-flagged distance plus the
    noise."""
    good = [i for i in range(len(case.slots)) if i != case.wrong]
    clean = [p for i, p in enumerate(case.taught.points) if i != case.wrong]
    ref = None
    if any(case.slots[i][2] == ON and case.slots[i][0] == case.slots[case.wrong][0] for i in good):
        try:
            fit = fit_station(case.truth.base, clean)
            ref = fit.station if fit.sound else None
        except TaughtPointsError:
            ref = None
    return gm.outcome(case, named_ref=ref, kept_ref=ref, slack_mm=NOISE_MM[1], named_mm=gm.TOWER_MM + NOISE_MM[1])


__all__ = ["RealLike", "files", "gross_cases", "lab_table", "outcome", "real_like", "recorded", "station", "taught"]
