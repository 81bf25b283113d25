"""The keys of an interactive teach session, and its loop: live status, keys to actions, messages.

The loop follows the driver (a jog step arriving, the driver gone) every :data:`POLL_S`, redraws the live status
every :data:`REDRAW_S`, and does what each key asks (:data:`KEY_HELP`); it returns when ``f`` finds every tower
taught. Ctrl-C (KeyboardInterrupt), a closed terminal or SIGTERM (:class:`~ur3hanoi.teach.terminal.TerminalGoneError`)
and a lost driver (:class:`~ur3hanoi.errors.DriverError`) leave it as exceptions: every record is already on disk.
"""

from __future__ import annotations

import time

from ur3hanoi.teach.feedback import finish_problem
from ur3hanoi.teach.jog import JOG_ACCEL_RAD_S2, JOG_SPEED_RAD_S, JOG_STEPS_MM
from ur3hanoi.teach.session import Teacher
from ur3hanoi.teach.stillness import STILL_TOL_DEG, STILL_WINDOW_S
from ur3hanoi.teach.terminal import Keys, Screen

POLL_S = 0.04
"""[s] how often the loop looks at the keys and the driver."""
REDRAW_S = 0.2
"""[s] how often the live status is redrawn."""

KEY_HELP: tuple[str, ...] = (
    "keys: Enter record the named pose | u undo the last point | s skip the named pose | a name an extra point "
    "(tower, then height) | f finish | h help | Ctrl-C stop (every point is saved; run again to continue)",
    f"jog where there is no pendant: x/X y/Y z/Z step +/- along the station's axes, r/R turn the tool about its axis, "
    f"1/2/3 step {'/'.join(f'{s:g}' for s in JOG_STEPS_MM)} mm (deg), g go above the named pose; joint speed "
    f"{JOG_SPEED_RAD_S:g} rad/s, acceleration {JOG_ACCEL_RAD_S2:g} rad/s^2",
    f"a pose is recorded only when no joint moved more than {STILL_TOL_DEG:g} deg in the last {STILL_WINDOW_S:g} s",
)
_AXES = {"x": (0, 1), "X": (0, -1), "y": (1, 1), "Y": (1, -1), "z": (2, 1), "Z": (2, -1)}
_STEPS = {"1": 0, "2": 1, "3": 2}


class _Picker:
    """``a``: the tower, then the height, each one digit."""

    def __init__(self, teacher: Teacher) -> None:
        self.teacher = teacher
        self.tower: int | None = None

    def key(self, ch: str) -> tuple[bool, list[str]]:
        """(still picking, lines) after key ``ch``."""
        base = self.teacher.base
        n = base.n_towers if self.tower is None else base.n_heights
        if not (ch.isdigit() and 1 <= int(ch) <= n):
            return False, ["extra point cancelled"]
        if self.tower is None:
            self.tower = int(ch) - 1
            return True, [f"extra point on tower {ch}: height (1-{base.n_heights})?"]
        return False, self.teacher.name_extra(self.tower, int(ch) - 1)


def _finish_problem(teacher: Teacher) -> str:
    """Why ``f`` cannot finish yet ("" when it can): the fit needs a contact on every tower, and nothing is written
    from a fit that is not sound (a wrong point that is its tower's only contact, say)."""
    have = {p.tower for p in teacher.taught.points if p.k == 0}
    lacking = [str(t + 1) for t in range(teacher.base.n_towers) if t not in have]
    if lacking:
        return (f"cannot finish yet: tower(s) {', '.join(lacking)} have no contact pose (the fit needs one on every "
                "tower); record them, or Ctrl-C to stop here (the points are saved)")
    problem = finish_problem(teacher.base, teacher.taught.taught(), teacher.accept)
    if problem:
        return f"cannot finish yet: {problem} (u undoes the last point; Ctrl-C stops here, the points are saved)"
    return ""


def _act(teacher: Teacher, ch: str) -> tuple[str, list[str]]:
    """("finish" | "pick" | "", lines) for key ``ch``."""
    if ch in "\r\n":
        return "", teacher.record()[1]
    if ch in _AXES:
        return "", teacher.jog(*_AXES[ch])
    if ch in "rR":
        return "", teacher.turn(1 if ch == "r" else -1)
    if ch in _STEPS:
        return "", teacher.set_step(_STEPS[ch])
    actions = {"u": teacher.undo, "s": teacher.skip, "g": teacher.go, "h": lambda: [*KEY_HELP, *teacher.extra_help]}
    if ch in actions:
        return "", actions[ch]()
    if ch == "a":
        return "pick", [f"extra point: tower (1-{teacher.base.n_towers})?"]
    if ch == "f":
        problem = _finish_problem(teacher)
        return ("", [problem]) if problem else ("finish", [])
    other = teacher.other_key(ch)
    if other is not None:
        return "", other
    if ch.isprintable() and not ch.isspace():
        return "", [f"key {ch!r} does nothing here (h shows the keys)"]
    return "", []


def run(teacher: Teacher, keys: Keys, screen: Screen) -> None:
    """Run the session until ``f`` finishes it (see the module docstring)."""
    screen.say([*KEY_HELP, *teacher.extra_help, teacher.next_line()])
    picker: _Picker | None = None
    next_draw = 0.0
    try:
        while True:
            screen.say(teacher.tick())
            now = time.monotonic()
            if now >= next_draw:
                screen.draw(teacher.status())
                next_draw = now + REDRAW_S
            for ch in keys.read(POLL_S):
                if picker is not None:
                    going, lines = picker.key(ch)
                    picker = picker if going else None
                    screen.say(lines)
                    continue
                what, lines = _act(teacher, ch)
                screen.say(lines)
                if what == "finish":
                    return
                if what == "pick":
                    picker = _Picker(teacher)
                next_draw = 0.0
    finally:
        screen.close()


__all__ = ["KEY_HELP", "POLL_S", "REDRAW_S", "run"]
