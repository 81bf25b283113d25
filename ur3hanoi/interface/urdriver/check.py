"""The check of a cell before its first move (``ur3hanoi check-arm --driver ur``), on the official UR driver.

Each check gives one :class:`Check` (``ok``, ``warn``, ``fail`` or ``skip``) and a line saying what was seen:

- ``driver``: the driver answers (joint states, ``io_states``, the trajectory action, ``set_io``: the link's connect);
- ``program``: the External Control program runs (the driver's latched ``robot_program_running``);
- ``controller``: the scaled trajectory controller can execute: ``running`` (ROS 1) or ``active`` (ROS 2) in the
  controller manager's list where the driver answers ``list_controllers``, else its action server answers; and the
  program runs (the drivers' ``controller_stopper`` stops it with the program);
- ``speed``: the speed slider (the driver's speed scaling with the arm at rest): above :data:`FIRST_RUN_SLIDER` a
  warning for a first run, 0 (paused) a failure;
- ``model``: the arm against the calibration's robot, by what the driver shows of it: its control rate (a CB3 UR3
  publishes joint states at 125 Hz, an e-Series UR3e at 500 Hz): a UR3 calibration on a UR3e is refused;
- ``home``: the distance of every joint from the calibration's home: within :data:`HOME_OK_RAD` ok, within
  :data:`HOME_FAR_RAD` a warning (the solve approaches at 25 % speed), farther a failure;
- ``suction`` (only with the operator's consent, the cup free): the output on (``io_states`` shows it), the vacuum
  sensor rising to at least half-way from the calibration's ``ain0_off`` to ``ain0_free``, the vacuum switch staying
  low (nothing under the cup), then off and the switch still low.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np

from ur3hanoi.errors import DriverError
from ur3hanoi.interface.urdriver.cell import CellLink, suction_text, switch_suction
from ur3hanoi.interface.urdriver.facts import CONTROLLER_JOINTS
from ur3hanoi.station.calibration import Station

Status = Literal["ok", "warn", "fail", "skip"]
FIRST_RUN_SLIDER = 0.25
"""The speed slider above which a first run is warned (a fraction)."""
HOME_OK_RAD = 0.05
"""[rad] a joint this close to home is at home."""
HOME_FAR_RAD = 0.5
"""[rad] a joint farther than this from home fails the check (the first move would be a long one nobody planned)."""
RATE_WINDOW_S = 1.0
"""[s] how long the joint states are counted to tell the controller's rate."""
E_SERIES_ABOVE_HZ = 250.0
"""[Hz] a joint-state rate above this is an e-Series controller (500 Hz), below a CB3 (125 Hz): the geometric mean."""
ACTIVE = ("active", "running")
"""A controller that executes: ROS 2's ``active``, ROS 1 ros_control's ``running``."""
PROGRAM_WAIT_S = 1.0
"""[s] how long the latched program state is waited for."""
SUCTION_SETTLE_S = 1.0
"""[s] how long the vacuum sensor is given to rise (or fall) after the output switched."""


@dataclass(frozen=True)
class Check:
    """One check: its ``name``, ``status``, the ``line`` saying what was seen, and the ``value`` measured (JSON)."""

    name: str
    status: Status
    line: str
    value: float | bool | str | None = None

    def as_dict(self) -> dict[str, object]:
        return {"name": self.name, "status": self.status, "line": self.line, "value": self.value}


def _wait(link: CellLink, seconds: float, until: Callable[[], bool]) -> bool:
    end = time.monotonic() + seconds
    while not until():
        if time.monotonic() > end:
            return False
        link.wait(0.02)
    return True


def check_program(link: CellLink) -> Check:
    _wait(link, PROGRAM_WAIT_S, lambda: link.program_running() is not None)
    running = link.program_running()
    if running is None:
        return Check("program", "warn", f"the driver on {link.where} published no robot_program_running within "
                                        f"{PROGRAM_WAIT_S:g} s: look at the pendant (External Control must run)")
    if not running:
        return Check("program", "fail", "the External Control program is stopped: start it on the pendant "
                                        "(Program > URCaps > External Control, play)", False)
    return Check("program", "ok", "the External Control program runs", True)


def check_controller(link: CellLink, program: Check) -> Check:
    state = link.controller_state()
    name = link_controller(link)
    if state is not None and state not in ACTIVE:
        return Check("controller", "fail", f"{name} is {state} (controller_manager): "
                                           + ("the driver stops it with the program: start the program"
                                              if program.status == "fail" else "activate it (switch_controller)"),
                     state)
    if program.status == "fail":
        return Check("controller", "fail", f"{name} does not execute while the program is stopped (its goals are "
                                           "refused)", state or False)
    how = f"{state} (controller_manager)" if state in ACTIVE else "its action server answers"
    return Check("controller", "ok", f"{name}: {how}" +
                 ("" if program.status == "ok" else " (whether the program runs is not known)"), state or True)


def link_controller(link: CellLink) -> str:
    """The trajectory controller's name, from its action's (``/scaled_pos_joint_traj_controller/...``)."""
    return link.action.strip("/").split("/")[0]


def check_speed(link: CellLink) -> Check:
    _wait(link, 0.5, lambda: link.latest().speed_scaling is not None)
    s = link.latest().speed_scaling
    if s is None:
        return Check("speed", "warn", "the driver published no speed scaling: set the pendant's slider to 25 % for a "
                                      "first run")
    pct = 100.0 * s
    if s <= 1e-3:
        return Check("speed", "fail", f"speed slider {pct:.0f} %: the arm is paused (press play, slider to 25 %)", s)
    if s > FIRST_RUN_SLIDER + 1e-3:
        return Check("speed", "warn", f"speed slider {pct:.0f} %: above {100 * FIRST_RUN_SLIDER:.0f} % for a first "
                                      "run: set it to 25 % on the pendant (100 % once a solve went well)", s)
    return Check("speed", "ok", f"speed slider {pct:.0f} %", s)


def joint_rate_hz(link: CellLink, window_s: float = RATE_WINDOW_S) -> float:
    """The driver's joint-state rate [Hz], counted over ``window_s``."""
    n0, t0 = link.history.count, time.monotonic()
    time.sleep(window_s)
    return (link.history.count - n0) / (time.monotonic() - t0)


def check_model(link: CellLink, station: Station, label: str) -> Check:
    rate = joint_rate_hz(link)
    robot = station.robot
    seen_e = rate > E_SERIES_ABOVE_HZ
    want_e = robot.control_rate_hz > E_SERIES_ABOVE_HZ
    arm = "an e-Series arm (UR3e, 500 Hz)" if seen_e else "a CB3 arm (UR3, 125 Hz)"
    if seen_e != want_e:
        return Check("model", "fail", f"the driver publishes joint states at {rate:.0f} Hz: {arm}, but {label} is "
                                      f"for the {robot.title} ({robot.control_rate_hz:g} Hz): refused; use a "
                                      "calibration for this arm (robot.model)", round(rate, 1))
    return Check("model", "ok", f"joint states at {rate:.0f} Hz: {arm}, as {label}'s {robot.title}", round(rate, 1))


def check_home(link: CellLink, station: Station) -> Check:
    q = link.latest().q
    if q is None:
        return Check("home", "fail", "no joint states")
    off = np.abs(q - station.q_home_array)
    j = int(off.argmax())
    far = float(off[j])
    where = f"{far:.3f} rad ({np.degrees(far):.1f} deg) from home at {CONTROLLER_JOINTS[j]}"
    if far <= HOME_OK_RAD:
        return Check("home", "ok", f"at home (every joint within {far:.3f} rad)", round(far, 4))
    if far <= HOME_FAR_RAD:
        return Check("home", "warn", f"{where}: the solve moves it home first at 25 % speed", round(far, 4))
    return Check("home", "fail", f"{where}: bring it home with the pendant before the first solve (farther than "
                                 f"{HOME_FAR_RAD:g} rad)", round(far, 4))


def check_suction(link: CellLink, station: Station) -> Check:
    """The suction round trip (see the module docstring): the cup must be free."""
    w, levels = station.wiring, station.suction
    half = levels.ain0_off + 0.5 * (levels.ain0_free - levels.ain0_off)

    def sensor() -> float:
        io = link.latest().io
        return float("nan") if io is None else io.analog_in[w.sensor_input][1]

    def switch() -> bool:
        io = link.latest().io
        return bool(io is not None and io.digital_in[w.switch_input])

    try:
        switch_suction(link, station, True)
        rose = _wait(link, SUCTION_SETTLE_S, lambda: sensor() >= half)
        on_text, held_on = suction_text(link, station), switch()
        switch_suction(link, station, False)
        fell = _wait(link, SUCTION_SETTLE_S, lambda: sensor() < half and not switch())
        off_text = suction_text(link, station)
    except DriverError as exc:
        return Check("suction", "fail", str(exc))
    if not rose:
        return Check("suction", "fail", f"on: {on_text}: the vacuum sensor stayed below {half:.2f} V (off "
                                        f"{levels.ain0_off:.2f} V, cup free {levels.ain0_free:.2f} V): is DO{w.output} "
                                        "the vacuum's pin (io.suction_output) and the air on?", on_text)
    if held_on:
        return Check("suction", "fail", f"on: {on_text}: the vacuum switch reads 1 with the cup free: something "
                                        f"under the cup, or DI{w.switch_input} is not the switch "
                                        "(io.vacuum_switch_input)", on_text)
    if not fell:
        return Check("suction", "fail", f"off: {off_text}: the vacuum did not fall within {SUCTION_SETTLE_S:g} s",
                     off_text)
    return Check("suction", "ok", f"on: {on_text}; off: {off_text} (the switch stayed low with the cup free)",
                 on_text)


def check_cell(link: CellLink, station: Station, label: str, suction: bool) -> list[Check]:
    """Every check on a connected ``link`` for ``station`` (named ``label``), the suction round trip only when
    ``suction`` (the operator consented, the cup free)."""
    program = check_program(link)
    checks = [program, check_controller(link, program), check_speed(link), check_model(link, station, label),
              check_home(link, station)]
    if suction:
        checks.append(check_suction(link, station))
    else:
        checks.append(Check("suction", "skip", "not tried (--suction switches it on and off: the cup must be free)"))
    return checks


__all__ = [
    "ACTIVE",
    "E_SERIES_ABOVE_HZ",
    "FIRST_RUN_SLIDER",
    "HOME_FAR_RAD",
    "HOME_OK_RAD",
    "Check",
    "Status",
    "check_cell",
    "check_controller",
    "check_home",
    "check_model",
    "check_program",
    "check_speed",
    "check_suction",
    "joint_rate_hz",
]
