"""The injection matrix of issue 33: exact taught points of a station from its own IK table, one gross error at a
time in every slot of a taught file, and what the calibration made of it.

Stations (the truth the points are taught on, and the base calibration given to ``calibrate``): the shipped
``lab_real`` (UR3, stacked), ``ur3e_sim`` (UR3e, stacked) and ``lab_sim`` (UR3, flat), each as it is and as a
hidden station: its towers turned and moved as a whole (the base still the shipped one), and each tower a little on
its own (at most :data:`HIDDEN_TOWER_MM`). Files: the minimal one (a contact per tower, as teach names them), the
shipped example's five slots, and seeded random ones of 4, 6, 7 and 9 points (above poses among them). Errors
(:data:`KINDS`): the home pose, another tower's pose, the pose of a slot one height off, one joint off by 2-10 deg,
a joint's sign flipped.

Each case's outcome (:func:`outcome`) is one of :data:`ALLOWED`:

- ``named``: written, the wrong point named first and left out, every contact of every tower within
  :data:`TOWER_MM` (3 mm) of the truth;
- ``refused``: nothing written (exit 2), the report names the wrong point first (and the error line names it:
  tests/calibrate/test_verdict.py);
- ``undecided``: nothing written, the message names the wrong point among the ones the points cannot tell apart;
- ``kept``: written with the wrong point in, every tower within the always-flagged 8 mm (plus the hidden towers'
  own offsets) of the truth: an error the evidence cannot see (an above pose's height is the approach itself; a
  tower taught once may stand a few mm from the layout);
- ``said`` (issue 37): written with the wrong point in, where it is its tower's only pose and moved that tower
  sideways only (a joint-1 offset or sign typo, a flat station's slot one height off along its row, a joint-5 offset
  within a tower's own tilt): nothing but the base's layout could see it, and real towers stand 12-105 mm from
  that. The output names the tower as resting on one pose and the pose that would check it (:func:`unseen`).

Anything else is a failure (``bent``, ``unnamed``, ``not first``...). ``python -m tests.support.gross_matrix [--fast]``
prints the counts (with ``PYTHONPATH`` naming another tree: that tree's counts).
"""

from __future__ import annotations

import math
import zlib
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from ur3hanoi.calibrate import fit_station
from ur3hanoi.calibrate.taught import TaughtPoint, TaughtPoints
from ur3hanoi.errors import TaughtPointsError
from ur3hanoi.station.calibration import Station, load_station
from ur3hanoi.station.grid import ABOVE, ON, contact_point_world
from ur3hanoi.tables.ik_table import generate_table

Slot = tuple[int, int, int]
KINDS = ("home", "tower", "height", "joint", "sign")
TOWER_MM = 3.0
"""[mm] a calibration written without the wrong point puts every contact this close to the truth."""
FLAG_MM = 8.0
"""[mm] the audit's always-flagged distance (:data:`ur3hanoi.calibrate.limits.CONTACT_FLAG_MM`)."""
HIDDEN_TOWER_MM = 1.5
"""[mm] how far each tower of a hidden station stands from its layout moved as a whole."""
ALLOWED = ("named", "refused", "undecided", "kept", "said")
HIDDEN = {"lab_real": (2.0, (5.0, -4.0, 1.0)), "ur3e_sim": (-1.5, (-6.0, 3.0, 0.5)), "lab_sim": (1.5, (4.0, 5.0, 0.0))}
"""Each shipped station's hidden twin: its towers turned [deg] about their centroid and moved [mm]."""


@dataclass(frozen=True)
class Truth:
    """A station the points are taught on (``truth``), the base calibration ``calibrate`` is given, and a name."""

    name: str
    base: Station
    truth: Station


def hidden(base: Station, turn_deg: float, shift_mm: tuple[float, float, float], seed: int) -> Station:
    """``base``'s towers turned about their centroid and moved as a whole, each then moved on its own by a seeded
    offset of at most :data:`HIDDEN_TOWER_MM`."""
    o = np.asarray(base.tower_origins, dtype=float)
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    rng = np.random.default_rng(seed)
    own = rng.normal(size=(len(o), 3))
    own *= (rng.uniform(0.0, HIDDEN_TOWER_MM, len(o)) / np.linalg.norm(own, axis=1))[:, None]
    moved = (o - o.mean(axis=0)) @ R.T + o.mean(axis=0) + (np.asarray(shift_mm) + own) * 1e-3
    return base.with_grid(moved, R @ np.asarray(base.height_step), base.tool_yaw)


def truths() -> list[Truth]:
    out = []
    for k, (name, (turn, shift)) in enumerate(HIDDEN.items()):
        base = load_station(name)
        out += [Truth(name, base, base), Truth(f"{name} hidden", base, hidden(base, turn, shift, k))]
    return out


def files(t: Truth) -> dict[str, list[Slot]]:
    """The taught files of a station: minimal, the example's slots, and seeded random ones of 4, 6, 7, 9 points."""
    n_t, n_h = t.base.n_towers, t.base.n_heights
    out = {"minimal": [(0, n_h - 1, ON), *((k, 0, ON) for k in range(1, n_t))],
           "example": [(0, 0, ON), (1, 0, ON), (2, 0, ON), (0, 2, ON), (2, 1, ABOVE)]}
    rng = np.random.default_rng(zlib.crc32(t.name.encode()))
    for n in (4, 6, 7, 9):
        slots: list[Slot] = [(k, int(rng.integers(n_h)), ON) for k in range(n_t)]
        rest = [(a, b, c) for a in range(n_t) for b in range(n_h) for c in (ON, ON, ABOVE) if (a, b, c) not in slots]
        for j in rng.permutation(len(rest)):
            if len(slots) == n:
                break
            if rest[int(j)] not in slots:
                slots.append(rest[int(j)])
        out[f"random{n}"] = slots
    return out


def inject(kind: str, q: np.ndarray, t: Truth, slot: Slot, rng: np.random.Generator) -> np.ndarray:
    """The joint values [rad] recorded for ``slot`` with the error ``kind`` (``q``: the truth's IK table)."""
    tw, h, k = slot
    if kind == "home":
        return t.truth.q_home_array.copy()
    if kind == "tower":
        return q[(tw + 1) % t.base.n_towers, h, k].copy()
    if kind == "height":
        return q[tw, h + 1 if h + 1 < t.base.n_heights else h - 1, k].copy()
    out = q[slot].copy()
    if kind == "joint":
        out[int(rng.integers(6))] += math.radians(float(rng.uniform(2.0, 10.0)) * float(rng.choice([-1.0, 1.0])))
    else:
        big = [j for j in range(6) if abs(out[j]) > math.radians(5.0)]
        j = int(rng.choice(big))
        out[j] = -out[j]
    return out


@dataclass(frozen=True)
class Case:
    """One taught file with one wrong point: the station, the file, the wrong point's index and the error."""

    truth: Truth
    file: str
    slots: tuple[Slot, ...]
    wrong: int
    kind: str
    taught: TaughtPoints

    @property
    def label(self) -> str:
        t, h, k = self.slots[self.wrong]
        return f"tower {t + 1} height {h + 1}{' above' if k == ABOVE else ''} [points[{self.wrong}]]"

    def __str__(self) -> str:
        return f"{self.truth.name} / {self.file} / {self.label} / {self.kind}"


def cases(t: Truth, chosen: dict[str, list[Slot]] | None = None, kinds: tuple[str, ...] = KINDS,
          every: int = 1) -> Iterator[Case]:
    """Every slot of every file of ``t`` (or of ``chosen``) with every error of ``kinds``; with ``every`` > 1 only
    one error per slot, taking turns through ``kinds``."""
    q = generate_table(t.truth).q
    for name, slots in (chosen or files(t)).items():
        rng = np.random.default_rng(zlib.crc32(f"{t.name}/{name}".encode()))
        for i, slot in enumerate(slots):
            for n, kind in enumerate(kinds):
                qs = [q[s].copy() for s in slots]
                qs[i] = inject(kind, q, t, slot, rng)
                if every > 1 and (n + i) % every:
                    continue
                points = tuple(TaughtPoint(index=j, tower=s[0], height=s[1], k=s[2], q=tuple(float(v) for v in qs[j]))
                               for j, s in enumerate(slots))
                yield Case(t, name, tuple(slots), i, kind, TaughtPoints(points=points, source="t.yaml", sha256=""))


def tower_error_mm(fitted: Station, truth: Station) -> float:
    """The largest distance [mm] between the two stations' contact points, over every tower and height."""
    return max(float(np.linalg.norm(contact_point_world(fitted, t, h) - contact_point_world(truth, t, h))) * 1e3
               for t in range(truth.n_towers) for h in range(truth.n_heights))


def outcome(case: Case, named_ref: Station | None = None, kept_ref: Station | None = None,
            slack_mm: float = HIDDEN_TOWER_MM, named_mm: float = TOWER_MM) -> tuple[str, str]:
    """(the outcome, what was said) of calibrating ``case`` (see the module docstring). ``named_ref``: where the
    good points put the towers (default: the truth), ``kept_ref``: where all the good points do (default: the truth),
    ``slack_mm``: how far the truth's towers may stand from their own points (the hidden towers' offsets, or the
    recording noise); ``named_mm``: how close a point named and left out leaves every tower to ``named_ref``."""
    try:
        fit = fit_station(case.truth.base, case.taught)
    except TaughtPointsError as exc:  # too little left to fit: the message lists what was left out
        return ("refused" if case.label.split(" [")[0] in str(exc) else "refused, unnamed"), str(exc)
    said = fit.problem or (fit.warnings[0] if fit.warnings else "")
    first = bool(fit.suspects) and fit.suspects[0].index == case.wrong
    if not fit.sound:  # the report names the suspects worst first, then the one error line says why
        if first:
            return "refused", said
        if case.wrong in getattr(fit, "named", ()) and case.label in fit.problem:
            return "undecided", said
        named = any(s.index == case.wrong for s in fit.suspects)
        return "refused, named not first" if named else "refused, unnamed", said
    if not fit.used[case.wrong]:
        worst = tower_error_mm(fit.station, named_ref or case.truth.truth)
        if not first and fit.consensus == "agree" and tower_error_mm(
                fit.station, kept_ref or case.truth.truth) <= FLAG_MM + slack_mm:
            return "kept", said  # within the station's scatter: the fit's finer pruning ranks it among noisy ones
        if not first:
            return "left out, named not first", said
        return ("named", said) if worst <= named_mm else (f"named, but a tower {worst:.1f} mm off", said)
    worst = tower_error_mm(fit.station, kept_ref or case.truth.truth)
    if worst <= FLAG_MM + slack_mm:
        return "kept", said
    if unseen(case, fit.station, fit.single_pose, slack_mm):
        return "said", said
    return f"written bent: a tower {worst:.1f} mm off", said


def unseen(case: Case, fitted: Station, single_pose: tuple[tuple[int, int, float], ...],
           slack_mm: float = HIDDEN_TOWER_MM) -> bool:
    """Whether the wrong point, written, moved only what no evidence sees, and the output says so (issue 37): its
    tower rests on it alone (named in :attr:`ur3hanoi.calibrate.result.CalibrationFit.single_pose`), and the
    calibration differs from the truth sideways only: every level within the always-flagged distance (plus the
    hidden towers' own offsets), and every good point's slot too (on a flat station whose step the points do not fix,
    a wrong end tower turns the row, and the untaught rows of the others with it)."""
    t_wrong = case.slots[case.wrong][0]
    if (t_wrong, case.wrong) not in {(t, i) for t, i, _ in single_pose}:
        return False
    truth, limit = case.truth.truth, FLAG_MM + slack_mm
    for t in range(truth.n_towers):
        for h in range(truth.n_heights):
            d = (contact_point_world(fitted, t, h) - contact_point_world(truth, t, h)) * 1e3
            taught = any(s[:2] == (t, h) for i, s in enumerate(case.slots) if i != case.wrong and s[0] != t_wrong)
            if abs(float(d[2])) > limit or (taught and float(np.linalg.norm(d)) > limit):
                return False
    return True


def tally(fast: bool = False) -> tuple[Counter[str], list[str]]:
    """Every case's outcome counted, and the failures described."""
    counts: Counter[str] = Counter()
    failures = []
    for t in truths():
        for case in (fast_cases(t) if fast else cases(t)):
            kind, said = outcome(case)
            counts[kind if kind in ALLOWED else f"FAIL {kind.split(':')[0]}"] += 1
            if kind not in ALLOWED:
                failures.append(f"{case}: {kind}: {said}")
    return counts, failures


def fast_cases(t: Truth) -> Iterator[Case]:
    """The fast phase's share: the minimal file with every error in every slot, and the random 6-point file with
    one error per slot (taking turns)."""
    chosen = files(t)
    yield from cases(t, {"minimal": chosen["minimal"]})
    yield from cases(t, {"random6": chosen["random6"]}, every=len(KINDS))


def main() -> int:
    import sys
    import time

    t0 = time.process_time()
    counts, failures = tally(fast="--fast" in sys.argv)
    print(f"{sum(counts.values())} cases in {time.process_time() - t0:.1f} s CPU")
    for kind, n in sorted(counts.items()):
        print(f"  {n:5d}  {kind}")
    for line in failures if "-v" in sys.argv else ():
        print(line)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
