"""What a student reads about the point the consensus named (:mod:`ur3hanoi.calibrate.consensus`): what is wrong
with it in their terms, and what to do.

What probably happened, tried in this order on the point's joint values and where the other points put its slot:

- the arm was **at home** (its joints are the base calibration's home pose, each within :data:`HOME_DEG`);
- a **copied entry** (the joint values of another slot, to the bit: copied, or recorded again without moving);
- the pose was **recorded in the wrong slot**: it stands where another slot of the grid is (another tower, a height
  off, on and above mixed up), within the always-flagged distance and with the others' suction axis;
- **a typo in one joint** (which joint, recorded and expected values; a **sign typo** when the expected value is
  the recorded one negated): one joint's change puts it where the others put its slot
  (:func:`ur3hanoi.calibrate.explain.joint_typo_point`, the audit's standard: it leaves at most a quarter of the
  error, and no more than the never-flagged distance and tilt);
- otherwise **the arm was not on the block**, with how the tool is turned from the others when it is.

Towers and heights are numbered from 1; every message says what to do once.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ur3hanoi.calibrate.consensus import Consensus
from ur3hanoi.calibrate.evidence import BY_LEVEL, HEADING_DEG, SPREAD_SIGMAS, Check, Evidence, Judgement
from ur3hanoi.calibrate.explain import (
    JOINT_LABELS,
    TYPO_SHARE,
    JointTypo,
    angle_text,
    joint_typo_level,
    joint_typo_point,
)
from ur3hanoi.calibrate.limits import CONTACT_FLAG_MM, CONTACT_OK_MM, TILT_FLAG_DEG, TILT_OK_DEG, table_axis
from ur3hanoi.calibrate.table_checks import TOWER_TILT_DEG
from ur3hanoi.calibrate.taught import TaughtPoint
from ur3hanoi.errors import printable
from ur3hanoi.robot.ik import wrap_angle
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.grid import ABOVE, ON, pose_label

HOME_DEG = 1.0
"""[deg] a pose whose every joint is this close to the base's home pose was recorded with the arm at home."""

LEVEL_TYPO_DEG = 1.0
"""[deg] a typo in one joint explains a tower's only contact when the change leaves its axis within this of the
others' (or a quarter of its tilt before): its place along the table gives no other check."""

Points = Sequence[TaughtPoint]


@dataclass(frozen=True)
class Named:
    """What is wrong with one point: ``what`` (in the student's terms), ``todo`` (what to do), ``explained`` (False
    when nothing but its place says it is wrong: the tower may really stand there)."""

    what: str
    todo: str
    explained: bool


def slot_text(p: TaughtPoint) -> str:
    """``tower 2 height 1 [points[1]]`` (``... above [...]`` for an above pose)."""
    return f"{pose_label(p.tower, p.height, p.k).removesuffix(' on')} [{p.where}]"


def accept_option(p: TaughtPoint) -> str:
    """The option that accepts ``p`` on the student's word: ``--accept 2,1``."""
    return f"--accept {p.tower + 1},{p.height + 1}"


def _grid_points(ev: Evidence, j: Judgement) -> dict[tuple[int, int, int], np.ndarray]:
    """Every slot's suction point [m] where the judged points put it (of the towers they place)."""
    out = {}
    for t in range(ev.base.n_towers):
        o = j.origins_m[t]  # a tower with no judged contact stands anywhere: no slot of it to compare with
        for h in range(ev.base.n_heights):
            out[(t, h, ON)] = o + h * j.step_m
            out[(t, h, ABOVE)] = out[(t, h, ON)] + np.array([0.0, 0.0, ev.base.approach])
    return {s: p for s, p in out.items() if not np.isnan(p[0])}


def _typo(ev: Evidence, p: TaughtPoint, i: int, target: np.ndarray, axis: np.ndarray, level: bool = False
          ) -> JointTypo | None:
    """The typo in one joint that explains point ``i``: one that moves it to ``target`` [m] (``level``: to its
    height only, for a tower's only contact) with the others' suction ``axis``."""
    robot = load_ur3(ev.base.tool, ev.base.limits, ev.base.robot)
    if level:
        typo = joint_typo_level(robot, ev.base.T_world_base, p.q, float(target[2]), axis, CONTACT_OK_MM, TILT_OK_DEG)
        err = abs(float(ev.m.p_world[i, 2] - target[2])) * 1e3
        # Only its height and axis say anything: the change must bring the axis back too, not tilt it to reach the
        # level (a pose hovering over its block is no typo of joint 2).
        before = math.degrees(math.acos(float(np.clip(ev.m.R_world[i, :, 2] @ axis, -1.0, 1.0))))
        if typo is not None and typo.residual_deg > max(LEVEL_TYPO_DEG, TYPO_SHARE * before):
            return None
    else:
        typo = joint_typo_point(robot, ev.base.T_world_base, p.q, target, axis, CONTACT_OK_MM, TILT_OK_DEG)
        err = float(np.linalg.norm(ev.m.p_world[i] - target)) * 1e3
    if typo is None or typo.residual_mm > min(CONTACT_OK_MM, TYPO_SHARE * err) or typo.residual_deg > TILT_OK_DEG:
        return None
    return typo


def _typo_named(typo: JointTypo) -> Named:
    j, rec, exp = typo.joint, typo.recorded, typo.predicted
    name = f"joint {j + 1} ({JOINT_LABELS[j]})"
    if typo.sign:
        return Named(f"likely a sign typo in {name}: recorded {math.degrees(rec):.1f} deg, the others put it at "
                     f"{-math.degrees(rec):.1f} deg", f"correct the sign of {name} or re-record it", True)
    return Named(f"likely a typo in {name}: recorded {angle_text(rec)}, the others put it at {angle_text(exp)} "
                 f"({math.degrees(exp - rec):+.1f} deg)", f"correct {name} or re-record it", True)


def _heading(ev: Evidence, chosen: Judgement, i: int) -> tuple[float, float]:
    """Point ``i``'s heading from the kept points' circular mean, and the limit past which it counts [deg]."""
    h = ev.m.heading[np.flatnonzero(chosen.kept)]
    if len(h) < 2:
        return 0.0, math.inf
    mean = math.atan2(float(np.mean(np.sin(h))), float(np.mean(np.cos(h))))
    spread = float(np.median(np.abs(np.degrees(wrap_angle(h - mean)))))
    off = abs(math.degrees(float(wrap_angle(ev.m.heading[i] - mean))))
    return off, max(HEADING_DEG, SPREAD_SIGMAS * spread)


def diagnose_named(ev: Evidence, chosen: Judgement, i: int, points: Points) -> Named:
    """What is wrong with point ``i``, judged against the points ``chosen`` kept (see the module docstring)."""
    p = points[i]
    home = np.abs(np.degrees(wrap_angle(np.asarray(p.q) - ev.base.q_home_array)))
    if float(np.max(home)) <= HOME_DEG:
        joints = ", ".join(f"{math.degrees(v):.0f}" for v in ev.base.q_home)
        return Named(f"its joints are the home pose of {ev.base_label} ({joints} deg): the arm was at "
                     "home when it was recorded", "move the arm onto the block and record it again", True)
    copy = next((o for o in points if o.index != p.index and o.q == p.q and
                 (o.tower, o.height, o.k) != (p.tower, p.height, p.k)), None)
    if copy is not None:
        return Named(f"it holds the joint values of {slot_text(copy)} (recorded again without moving the arm, or "
                     "copied)", "record it in its own slot", True)
    kept_on = [k for k in np.flatnonzero(chosen.kept) if ev.slots[k][2] == ON]
    axis = table_axis(ev.m.R_world[kept_on, :, 2])
    tilt = math.degrees(math.acos(float(np.clip(ev.m.R_world[i, :, 2] @ axis, -1.0, 1.0))))
    others = {s: float(np.linalg.norm(ev.m.p_world[i] - g)) * 1e3 for s, g in _grid_points(ev, chosen).items()
              if s != (p.tower, p.height, p.k)}
    if others and tilt <= TILT_FLAG_DEG:
        slot = min(others, key=lambda s: others[s])
        if others[slot] <= CONTACT_FLAG_MM:
            return Named(f"it stands where {pose_label(*slot).removesuffix(' on')} is ({others[slot]:.1f} mm off): "
                         "probably recorded in the wrong slot",
                         "record it in its own slot or correct its tower and height", True)
    level = chosen.by[i] == BY_LEVEL
    target = (np.array([np.nan, np.nan, chosen.level_m[p.height]]) if level and p.k == ON else chosen.expected_m[i])
    typo = None if np.isnan(target[2]) or (np.isnan(target[0]) and not level) else _typo(ev, p, i, target, axis,
                                                                                            level)
    if typo is not None:
        return _typo_named(typo)
    turned = [f"its suction axis is {tilt:.1f} deg from the others'"] if tilt > TILT_FLAG_DEG else []
    off, limit = _heading(ev, chosen, i)
    if off > limit:
        turned.append(f"the tool is turned {off:.0f} deg from the others' heading")
    how = f" ({'; '.join(turned)})" if turned else ""
    where = "on the block" if p.k == ON else "over its block at the others' approach height"
    return Named(f"no single joint explains it: the arm was not {where}{how}", "re-record it", bool(turned))


def _judgement(c: Consensus, i: int) -> Judgement:
    """The points judged without the named point ``i``."""
    return c.chosen if c.wrong and i == c.wrong[0] else c.tried[i]


def where_text(ev: Evidence, c: Consensus, i: int) -> str:
    """``15.9 mm from where the other points put it`` (for its tower's only contact: ``31.8 mm off the level where
    the other towers put height 1 (...)``)."""
    j = _judgement(c, i)
    if j.by[i] == BY_LEVEL:
        p = ev.slots[i]
        return (f"{j.off_mm[i]:.1f} mm off the level where the other towers put height {p[1] + 1} (one flat table, "
                f"blocks of {ev.base_label})")
    return f"{j.off_mm[i]:.1f} mm from where the other points put it"


def named_text(ev: Evidence, c: Consensus, i: int, points: Points) -> str:
    """What is wrong with the named point ``i`` and what to do: ``likely a typo in joint 2 (shoulder): ...;
    correct joint 2 (shoulder) or re-record it``."""
    n = diagnose_named(ev, _judgement(c, i), i, points)
    return f"{n.what}; {n.todo}"


def refusal(ev: Evidence, c: Consensus, points: Points) -> str:
    """Why nothing is written: the named point is its tower's only contact, or the points cannot tell which of
    several is wrong."""
    if c.kind == "named":
        i = c.wrong[0]
        p = points[i]
        n = diagnose_named(ev, c.chosen, i, points)
        out = (f"{slot_text(p)} is {where_text(ev, c, i)}; {n.what}. It is the only contact of tower {p.tower + 1}, "
               f"so nothing is written without it: {n.todo}")
        if not n.explained and c.chosen.by[i] == BY_LEVEL:
            out += f" (if tower {p.tower + 1} really stands there, run again with {accept_option(p)})"
        return out
    named = [f"{slot_text(points[i])} ({c.tried[i].off_mm[i]:.1f} mm off)" for i in c.wrong]
    towers = sorted({points[i].tower + 1 for i in c.wrong})
    more = f", or teach another height of tower {towers[0]} to decide" if len(towers) == 1 else ""
    return (f"the points cannot tell which of {' and '.join(named)} is wrong: leaving out any one of them leaves the "
            f"others consistent (within {CONTACT_FLAG_MM:g} mm of where they put each other, on one flat table, "
            f"towers apart): re-record them{more}")


def _check_text(ev: Evidence, c: Check, points: Points) -> str:
    what, index, value = c.what, c.index, c.value
    if what == "level":
        return (f"tower {index + 1} stands {abs(value):.1f} mm {'higher' if value > 0 else 'lower'} than the other "
                "towers (one flat table)")
    if what == "lean":
        return (f"the suction axis at tower {index + 1} is {value:.1f} deg from the other towers' (more than "
                f"{TOWER_TILT_DEG:g} deg)")
    if what == "distinct":
        return (f"towers {index + 1} and {c.other + 1} stand {value:.1f} mm apart (less than a block, "
                f"{ev.base.block_size * 1e3:.1f} mm)")
    if what == "step":
        return (f"the step between levels puts the top level {value:.1f} mm from where the block size of "
                f"{ev.base_label} puts it")
    if what == "point":
        return f"{slot_text(points[index])} is {value:.1f} mm from where the other points put it"
    if what == "tilt":
        return f"the suction axis of {slot_text(points[index])} is {value:.1f} deg from its tower's other contacts'"
    if what == "above":
        return f"{slot_text(points[index])} is {value:.1f} mm off its tower's vertical line"
    if what == "approach":
        return f"{slot_text(points[index])} stands {value:.1f} mm higher or lower over its contact than the others"
    return f"{slot_text(points[index])} stands {value:.1f} mm over its contact"


def unexplained(ev: Evidence, j: Judgement, points: Points) -> str:
    """Why the points ``j`` kept do not agree when no single point explains it ("" when they do)."""
    said = [_check_text(ev, c, points) for c in j.checks if c.over and not c.soft]
    if not said:
        return ""
    more = f" and {len(said) - 3} more" if len(said) > 3 else ""
    return (f"no single point explains the disagreement ({'; '.join(said[:3])}{more}): check the tower/height labels "
            f"and that {ev.base_label} is this station's calibration (robot base, tool, block size)")


def accepted_lines(points: Points, accepted: Sequence[tuple[int, float]], base_label: str) -> list[str]:
    """One line per point taken on the student's word (``accepted``: index, mm from where the base's layout puts
    its tower, :attr:`ur3hanoi.calibrate.result.CalibrationFit.accepted`)."""
    out = []
    for i, mm in accepted:
        p = points[i]
        far = ("" if math.isnan(mm) else f": {mm:.1f} mm from where the layout of {printable(base_label)}, moved and "
               "turned onto the other towers, puts it")
        out.append(f"tower {p.tower + 1} placed by {slot_text(p)} on your word ({accept_option(p)}){far}")
    return out


def single_pose_lines(points: Points, single_pose: Sequence[tuple[int, int, float]]) -> list[str]:
    """One line per tower whose place rests on one pose (:attr:`ur3hanoi.calibrate.result.CalibrationFit.
    single_pose`): what nothing checks, and the pose that would."""
    out = []
    for t, i, lean in single_pose:
        p = points[i]
        tilt = (f"; its suction axis is {lean:.1f} deg from the other towers' (the tower's own tilt, or a wrong pose: "
                "one pose cannot tell)" if lean > TILT_FLAG_DEG else "")
        out.append(f"tower {t + 1} rests on one pose, {slot_text(p)}: nothing checks where it stands along the table "
                   f"(a joint-1 offset would move it with nothing else changed){tilt}; record "
                   f"{pose_label(t, p.height, ABOVE)} (or a second height of tower {t + 1}) to check it")
    return out


def note_lines(points: Points, accepted: Sequence[tuple[int, float]], single_pose: Sequence[tuple[int, int, float]],
               base_label: str) -> list[str]:
    """What a written calibration rests on without a check: the points taken on the student's word, the towers
    resting on one pose."""
    return [*accepted_lines(points, accepted, base_label), *single_pose_lines(points, single_pose)]


__all__ = ["HOME_DEG", "LEVEL_TYPO_DEG", "Named", "accept_option", "accepted_lines", "diagnose_named", "named_text",
           "note_lines", "refusal", "single_pose_lines", "slot_text", "unexplained", "where_text"]
