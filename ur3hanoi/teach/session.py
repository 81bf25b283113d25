"""One teach session: the poses named, recorded, undone and skipped, the jog steps, and what is said about each.

:class:`Teacher` holds the session's state and does what a key asks (record, undo, skip, name an extra slot, jog,
go, change the step); each action returns the lines to show. It knows nothing of terminals: the interactive
front end (:mod:`ur3hanoi.teach.interactive`) maps keys to actions, the command line's ``--record-now`` calls
:meth:`Teacher.record` once.

Recording takes the newest published pose, only when the arm is still (:mod:`ur3hanoi.teach.stillness`) and no jog
step is under way, writes the file at once (:mod:`ur3hanoi.teach.taught_file`), and from the third point on shows
the feedback (:mod:`ur3hanoi.teach.feedback`); then the next pose is named (:mod:`ur3hanoi.teach.advice`). A jog
step waits for the arm to arrive before the next one is taken (a key pressed meanwhile is dropped, so a held key
never queues motion); on the real driver the first motion key only says what jogging does there.
"""

from __future__ import annotations

import math
import time
from collections.abc import Collection
from dataclasses import dataclass

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import printable
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ON, contact_point_world
from ur3hanoi.teach.advice import Advice, next_pose
from ur3hanoi.teach.driver import Driver, DriverNames, latest
from ur3hanoi.teach.feedback import FIRST_FEEDBACK, feedback
from ur3hanoi.teach.jog import (
    JOG_ACCEL_RAD_S2,
    JOG_SPEED_RAD_S,
    JOG_STEPS_MM,
    Jogger,
    JogTarget,
    move_time_s,
)
from ur3hanoi.teach.stillness import STILL_WINDOW_S, stillness
from ur3hanoi.teach.taught_file import TaughtFile

ARRIVED_RAD = 2e-4
"""[rad] a jog step has arrived when every joint is this close to its target."""
ARRIVAL_MARGIN_S = 5.0
"""[s] a jog step not arrived this long after its motion should have ended is given up (the course's ROS 2 bridge
takes 2 s for any move)."""


@dataclass(frozen=True)
class _Move:
    """A jog move under way: its target [rad], what it is, and when to give up [s, monotonic]."""

    target: FloatArray
    what: str
    deadline: float


def _mm(p_m: FloatArray) -> str:
    x, y, z = (float(v) * 1e3 for v in p_m)
    return f"x {x:.1f} y {y:.1f} z {z:.1f} mm"


class Teacher:
    """The session's state (see the module docstring).

    Args:
        base: the base calibration (robot base, tool, grid the poses are named in).
        base_label: how messages name it.
        taught: the session's file (maybe continued).
        driver: the connected driver; names: how messages name it.
        start: the tower holding the blocks (0-based).
        accept: the ``(tower, height)`` slots (0-based) whose contacts the student vouches for (``--accept``).
    """

    def __init__(self, base: Station, base_label: str, taught: TaughtFile, driver: Driver, names: DriverNames,
                 start: int, accept: Collection[tuple[int, int]] = ()) -> None:
        self.base, self.base_label, self.taught = base, base_label, taught
        self.driver, self.names, self.start = driver, names, start
        self.accept = frozenset(accept)  # (tower, height) 0-based: contacts taken on the student's word
        self.jogger = Jogger(base)
        self.simulated = driver.simulated()  # asked once: a master lost later must not make it the real arm
        self.skipped: set[tuple[int, int]] = set()
        self.extra: Advice | None = None  # a pose named by hand (a), or a suspect to re-record
        self.step_index = 1
        self.move: _Move | None = None
        self.last_target: FloatArray | None = None  # the last jog target reached: steps add up exactly from it
        self.record_hint = "Enter records it"
        self.warned_real = False
        self.named: Advice | None = None
        self.extra_help: tuple[str, ...] = ()  # a driver's own keys (teach.ur_driver)
        self._advise()

    # ------------------------------------------------------------------------------------------------- naming
    def _advise(self) -> None:
        if self.extra is not None:
            self.named = self.extra
        else:
            self.named = next_pose(self.base, self.taught.slots, self.start, self.skipped)

    def next_line(self) -> str:
        """``next: tower 2 height 1 (why)``, or what to do when nothing is named."""
        if self.named is None:
            return ("next: nothing more to suggest: f finishes (a extra point, u undo)" if self.taught.points else
                    "next: nothing named (every required pose skipped): a names a pose")
        p = contact_point_world(self.base, self.named.tower, self.named.height)
        return (f"next: {self.named.label}: {self.named.why}; {printable(self.base_label)} puts it at {_mm(p)}; "
                f"{self.record_hint}")

    # -------------------------------------------------------------------------------------------------- state
    def q(self) -> FloatArray:
        """The newest published pose [rad] (raises :class:`~ur3hanoi.errors.DriverError` when the driver is gone)."""
        return latest(self.driver, self.names)[1]

    def tick(self) -> list[str]:
        """Check the driver and follow a jog move: the lines to show when it arrived or was given up."""
        q = self.q()
        if self.move is None:
            return []
        if float(np.max(np.abs(q - self.move.target))) < ARRIVED_RAD:
            what, self.last_target, self.move = self.move.what, self.move.target, None
            return [f"{what}: done, suction point at {_mm(self.jogger.H_world_tcp(q)[:3, 3])}"]
        if time.monotonic() > self.move.deadline:
            what, self.move = self.move.what, None
            return [f"{what}: the arm did not get there in time (is the driver executing {self.names.command}?)"]
        return []

    def status(self) -> list[str]:
        """The live lines: joint angles [deg], still or moving, the suction point [mm], the named pose's offset."""
        q = self.q()
        now = time.monotonic()
        still = stillness(self.driver.samples(STILL_WINDOW_S + 0.2), now)
        if self.move is not None or not (still.still or math.isnan(still.moved_deg)):
            state = "moving"
        else:
            state = "still" if still.still else "waiting for positions"
        p = self.jogger.H_world_tcp(q)[:3, 3]
        lines = [f"joints [deg] {' '.join(f'{v + 0.0:8.2f}' for v in np.round(np.degrees(q), 2))}   {state}",
                 f"suction point {_mm(p)}   jog step {JOG_STEPS_MM[self.step_index]:g} mm"]
        if self.named is not None:
            d = (contact_point_world(self.base, self.named.tower, self.named.height) - p) * 1e3
            lines.append(f"{self.named.label} ({printable(self.base_label)}) is dx {d[0]:+.1f} dy {d[1]:+.1f} "
                         f"dz {d[2]:+.1f} mm from here")
        return lines

    # ------------------------------------------------------------------------------------------------ actions
    def record(self) -> tuple[bool, list[str]]:
        """Record the named pose from the published one if the arm is still: (recorded, lines)."""
        if self.named is None:
            return False, ["nothing is named to record: a names a pose (tower, then height)"]
        if self.move is not None:
            return False, [f"the arm is moving ({self.move.what} under way): nothing recorded"]
        q = self.q()
        still = stillness(self.driver.samples(STILL_WINDOW_S + 0.2), time.monotonic())
        if not still.still:
            return False, [f"{still.why}: nothing recorded"]
        named = self.named
        self.taught, said = self.taught.with_point(named.tower, named.height, tuple(float(v) for v in q))
        self.taught.save()
        p = self.jogger.H_world_tcp(q)[:3, 3]
        lines = [f"{said}; suction point at {_mm(p)}"]
        self.extra = None
        self.skipped.discard((named.tower, named.height))
        if len(self.taught.points) >= FIRST_FEEDBACK:
            fb = feedback(self.base, self.taught.taught(), self.base_label, self.accept)
            lines += fb.lines(self.base_label)
            if fb.suspects:
                point = self.taught.points[fb.suspects[0][0]]
                self.extra = Advice(point.tower, point.height, False, "suspect: record it again (u undoes the last "
                                                                      "point instead)")
        self._advise()
        lines.append(self.next_line())
        return True, lines

    def undo(self) -> list[str]:
        self.taught, said = self.taught.without_last()
        self.taught.save()
        self.extra = None
        self._advise()
        return [said, self.next_line()]

    def skip(self) -> list[str]:
        if self.named is None:
            return ["nothing is named to skip"]
        self.skipped.add((self.named.tower, self.named.height))
        needed = " (the fit needs it: finish will say so)" if self.named.required else ""
        said = f"skipped {self.named.label}{needed}"
        self.extra = None
        self._advise()
        return [said, self.next_line()]

    def name_extra(self, tower: int, height: int) -> list[str]:
        """Name (tower, height) (0-based) as the pose to record next."""
        self.extra = Advice(tower, height, False, "the extra point you chose")
        self._advise()
        return [self.next_line()]

    def set_step(self, index: int) -> list[str]:
        self.step_index = index
        return [f"jog step {JOG_STEPS_MM[index]:g} mm (a turn {JOG_STEPS_MM[index]:g} deg)"]

    def _motion_allowed(self) -> list[str] | None:
        """Lines that stop a motion key (a move under way, the real driver's first key), or None to go on."""
        if self.move is not None:
            return [f"the arm is still moving ({self.move.what}): key dropped"]
        if not self.warned_real and not self.simulated:
            self.warned_real = True
            return [f"this driver is not ur3hanoi's station: jog keys move the real arm through {self.names.command} "
                    f"at {np.degrees(JOG_SPEED_RAD_S):.0f} deg/s; the pendant's freedrive is the normal way to teach. "
                    "Press the key again to step"]
        return None

    def _jog_from(self) -> FloatArray:
        """Where a step starts: the last jog target while the arm stands there (steps then add up exactly, not
        with the servo's last fraction of a millimetre), else the published pose."""
        q = self.q()
        if self.last_target is not None and float(np.max(np.abs(q - self.last_target))) < ARRIVED_RAD:
            return self.last_target
        return q

    def _send(self, target: JogTarget, what: str) -> list[str]:
        if target.q is None:
            return [target.reason]
        q = self.q()
        self.driver.send(target.q, JOG_SPEED_RAD_S, JOG_ACCEL_RAD_S2)
        self.move = _Move(target.q, what, time.monotonic() + move_time_s(q, target.q) + ARRIVAL_MARGIN_S)
        return [f"{what} to {_mm(target.p_world_m)} ..."]

    def jog(self, axis: int, sign: int) -> list[str]:
        """One step along world axis ``axis`` (0 x, 1 y, 2 z), ``sign`` +1 or -1."""
        stop = self._motion_allowed()
        if stop is not None:
            return stop
        step = sign * JOG_STEPS_MM[self.step_index]
        delta = [0.0, 0.0, 0.0]
        delta[axis] = step
        target = self.jogger.step(self._jog_from(), (delta[0], delta[1], delta[2]))
        return self._send(target, f"jog {'xyz'[axis]} {step:+g} mm")

    def turn(self, sign: int) -> list[str]:
        stop = self._motion_allowed()
        if stop is not None:
            return stop
        angle = sign * JOG_STEPS_MM[self.step_index]
        return self._send(self.jogger.step(self._jog_from(), turn_deg=angle), f"turn {angle:+g} deg")

    def go(self) -> list[str]:
        """Move above the named pose, where the base calibration puts it."""
        if self.named is None:
            return ["nothing is named to go to"]
        stop = self._motion_allowed()
        if stop is not None:
            return stop
        t, h = self.named.tower, self.named.height
        return self._send(self.jogger.go_above(self.q(), self.base, t, h), f"go above {self.named.label}")

    def other_key(self, ch: str) -> list[str] | None:
        """A driver's own key (teach.ur_driver): its lines, or None when ``ch`` is not one."""
        return None

    @property
    def contacts(self) -> int:
        return sum(1 for p in self.taught.points if p.k == ON)


__all__ = ["ARRIVAL_MARGIN_S", "ARRIVED_RAD", "Teacher"]
