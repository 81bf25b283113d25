"""``ur3hanoi check-arm``: the cell checked before its first move, one line per check (the checks:
:mod:`ur3hanoi.interface.urdriver.check` on the official UR driver; on the course's topics what they can tell).

The lines are the command's result: on stdout, or with ``--json`` one JSON object on stdout and the lines on stderr.
Exit 0 when nothing failed (warnings allowed), 2 when a check failed or the driver did not answer.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import TYPE_CHECKING, Any

from ur3hanoi.cli import exit_codes
from ur3hanoi.cli.options import DRIVER_WAIT, option
from ur3hanoi.cli.ros2 import add_dds_options
from ur3hanoi.cli.teach_ur import add_teach_driver_options

if TYPE_CHECKING:
    from ur3hanoi.interface.urdriver.check import Check
    from ur3hanoi.station.calibration import Station

_DESCRIPTION = (
    "Checks the cell before the first move, one line per check: the driver answering, the External Control program "
    "running, the scaled trajectory controller, the speed slider (a warning above 25 % for a first run), the arm's "
    "model against the calibration's robot (by the controller's rate: 125 Hz CB3 UR3, 500 Hz e-Series UR3e), the "
    "distance from home and, with --suction, a suction round trip with the cup free. Nothing moves the arm. With "
    "--driver course (the course's topics) only the driver and the distance from home can be told. Exit 0 when no "
    "check failed (warnings allowed), 2 when one did.")


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-arm", help="check the cell before the first move (driver, program, slider, model, "
                                         "home, suction)", description=_DESCRIPTION)
    p.add_argument("--via", required=True, choices=("ros", "ros2"), help="the middleware: ros (ROS 1) or ros2")
    p.add_argument("--calibration", required=True, metavar="CALIBRATION",
                   help="the station's calibration (a file or a shipped name): its robot, home and suction wiring")
    p.add_argument("--suction", action="store_true",
                   help="also switch the suction on and off (the cup must be free: nothing under it) and check the "
                        "vacuum sensor rises, the switch stays low and both fall back")
    p.add_argument("--json", action="store_true", help="one JSON object on stdout (the lines go to stderr)")
    p.add_argument("--wait", type=option(DRIVER_WAIT), default=10.0, metavar="S",
                   help="wait at most S seconds for the driver (default 10)")
    p.add_argument("--master", metavar="URI", help="with --via ros: ROS master URI (default: $ROS_MASTER_URI, else "
                                                   "http://localhost:11311)")
    add_dds_options(p)
    add_teach_driver_options(p)
    p.set_defaults(func=run)


def _label(name: str) -> str:
    from pathlib import Path

    return Path(name).name


def _ur_checks(args: argparse.Namespace, station: Station) -> list[Check]:
    from ur3hanoi.cli.teach_ur import cell_link
    from ur3hanoi.errors import DriverError
    from ur3hanoi.interface.urdriver.check import Check, check_cell

    link = cell_link(args)
    try:
        try:
            link.connect()
        except DriverError as exc:
            return [Check("driver", "fail", str(exc))]
        first = Check("driver", "ok", f"the UR driver answers on {link.where}: joint states, io_states, the "
                                      "trajectory action, set_io")
        return [first, *check_cell(link, station, _label(args.calibration), args.suction)]
    finally:
        link.close()


def _course_checks(args: argparse.Namespace, station: Station) -> list[Check]:
    import contextlib

    from ur3hanoi.cli.teach import _connect
    from ur3hanoi.errors import DriverError
    from ur3hanoi.interface.urdriver.check import Check

    try:
        with contextlib.redirect_stdout(sys.stderr):  # its progress line; stdout is the checks'
            arm, names = _connect(args, station)
    except DriverError as exc:
        return [Check("driver", "fail", str(exc))]
    try:
        q = arm.samples(1.0)
        home = _course_home(q, station)
        checks = [Check("driver", "ok", f"the course's driver publishes {names.position} on {names.where}"), home]
    finally:
        arm.close()
    told = "the course's topics do not tell it: look at the pendant"
    checks += [Check(n, "skip", told) for n in ("program", "controller", "speed", "model")]
    checks.append(Check("suction", "skip", "the course's topics switch it in ur3/command: try it in teach"))
    return checks


def _course_home(samples: list[tuple[float, Any]], station: Station) -> Check:
    import numpy as np

    from ur3hanoi.interface.urdriver.check import HOME_FAR_RAD, HOME_OK_RAD, Check, Status

    if not samples:
        return Check("home", "fail", "no position")
    far = float(np.max(np.abs(samples[-1][1] - station.q_home_array)))
    status: Status = "ok" if far <= HOME_OK_RAD else "warn" if far <= HOME_FAR_RAD else "fail"
    return Check("home", status, f"{far:.3f} rad from home (largest joint)", round(far, 4))


def run(args: argparse.Namespace) -> int:
    from ur3hanoi.cli.options import UsageError
    from ur3hanoi.station.calibration import load_station

    if args.master is not None and args.via != "ros":
        raise UsageError("--master is only used with --via ros")
    if args.ros_distro is not None and (args.driver != "ur" or args.via != "ros2"):
        raise UsageError("--ros-distro is only used with --via ros2 --driver ur")
    station = load_station(args.calibration)
    checks = _course_checks(args, station) if args.driver == "course" else _ur_checks(args, station)
    failed = [c.name for c in checks if c.status == "fail"]
    lines = "\n".join(f"{c.status:<5} {c.name:<10} {c.line}" for c in checks)
    verdict = (f"check-arm: {len(failed)} check(s) failed ({', '.join(failed)}): fix them before the first move"
               if failed else "check-arm: ready for the first move" +
               (" (read the warnings)" if any(c.status == "warn" for c in checks) else ""))
    if args.json:
        print(lines, verdict, sep="\n", file=sys.stderr)
        print(json.dumps({"ok": not failed, "driver": args.driver, "via": args.via,
                          "calibration": args.calibration, "checks": [c.as_dict() for c in checks]}))
    else:
        print(lines, verdict, sep="\n")
    sys.stdout.flush()
    return exit_codes.BAD_INPUT if failed else exit_codes.OK
