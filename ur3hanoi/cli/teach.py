"""``ur3hanoi teach``: record the taught poses from the arm's driver in a guided terminal session, then calibrate,
write the lab table and say what to run next (the session itself is :mod:`ur3hanoi.teach`).

Exit codes as everywhere: 0 done, 2 bad input or a driver lost (one line; what was recorded is saved), 130 Ctrl-C
(the points are saved: the same command continues), 129 the terminal closed, 143 SIGTERM.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ur3hanoi.cli import exit_codes
from ur3hanoi.cli.common import SYMLINK_NOTE, input_file, shown
from ur3hanoi.cli.options import (
    ACCEPT_HELP,
    DRIVER_WAIT,
    TABLE_KEYS,
    UsageError,
    check_accept,
    check_number,
    option,
    slot,
    station_number,
)
from ur3hanoi.cli.ros2 import add_dds_options
from ur3hanoi.cli.teach_ur import add_teach_driver_options

if TYPE_CHECKING:
    from ur3hanoi.station.calibration import Station
    from ur3hanoi.teach.driver import DriverNames
    from ur3hanoi.teach.taught_file import TaughtFile

FIRST_SOLVE_SPEED = 0.5
"""[rad/s], [rad/s^2] ``--v``/``--a`` of the first solve suggested on a new table: an eighth of the lab's 4."""
HANGUP, TERMINATED = 129, 143

_DESCRIPTION = (
    "A guided session in a plain terminal: connects to the running driver (ros-station, ros2-station or the "
    "course's real driver), shows the six joint angles [deg] and where the suction point is [mm], names the pose "
    "to record next and why, and records the published pose on Enter when the arm is still (no joint moving more "
    "than 0.05 deg in 0.5 s). Every record is written to TAUGHT at once (taught-points format, degrees; "
    "`calibrate --taught` reads it); running teach again on TAUGHT continues it. From the third point on, every "
    "point's residual and the suspects are shown. Without a pendant, keys jog the suction point by IK (1/5/20 mm, "
    "20 deg/s). At the end (f) it writes the calibration, the table key into --table (keeping its other keys), the "
    "audit and the next command. Towers and heights are numbered from 1.")


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("teach", help="record taught poses from the robot's driver, guided, then calibrate",
                       description=_DESCRIPTION)
    p.add_argument("--via", required=True, choices=("ros", "ros2"),
                   help="the driver: ros (ur3/* topics: ros-station or the course's ur3_driver) or ros2 (ur3e/*: "
                        "ros2-station or the course's bridge)")
    p.add_argument("--base", required=True, metavar="CALIBRATION",
                   help="station calibration giving robot base, tool, blocks and the towers' approximate places "
                        "(a file or a shipped name: lab_real, ur3e_sim)")
    p.add_argument("-o", "--output", required=True, metavar="TAUGHT",
                   help=f"taught-points YAML, rewritten at every record ({SYMLINK_NOTE}); continued when it exists")
    p.add_argument("--station-out", metavar="FILE",
                   help="calibration written at the end (default: TAUGHT's name with _station.yaml)")
    p.add_argument("--table", metavar="FILE",
                   help="lab file (lab2_data.yaml) to write the table key into at the end, keeping its other keys")
    p.add_argument("--key", choices=TABLE_KEYS, default=None, help="table key with --table (default real_pos)")
    p.add_argument("--start", type=station_number("a tower"), default=1, metavar="T",
                   help="tower the blocks stand on: it is taught on its top block (default 1)")
    p.add_argument("--wait", type=option(DRIVER_WAIT), default=10.0, metavar="S",
                   help="wait at most S seconds for the driver (and, with --record-now, for the arm to be still); "
                        "default 10")
    p.add_argument("--record-now", type=slot, metavar="T,H",
                   help="no terminal session: record the pose the driver publishes now as tower T height H "
                        "(waits until the arm is still), print the feedback and exit")
    p.add_argument("--accept", type=slot, action="append", metavar="T,H", help=ACCEPT_HELP)
    p.add_argument("--finish", action="store_true",
                   help="fit TAUGHT and write the outputs (no driver needed; after --record-now: after recording)")
    p.add_argument("--master", metavar="URI", help="with --via ros: ROS master URI (default: $ROS_MASTER_URI, else "
                                                   "http://localhost:11311)")
    add_dds_options(p)
    add_teach_driver_options(p)
    p.set_defaults(func=run)


def _check_options(args: argparse.Namespace) -> None:
    if args.key is not None and args.table is None:
        raise UsageError("--key is only used with --table")
    if args.master is not None and args.via != "ros":
        raise UsageError("--master is only used with --via ros")
    if args.driver == "ur" and args.via == "ros2" and args.convention != "course":
        raise UsageError("--convention is only used with --driver course: the UR driver's joint_states are named")
    if args.ros_distro is not None and (args.driver != "ur" or args.via != "ros2"):
        raise UsageError("--ros-distro is only used with --via ros2 --driver ur")


def _names(args: argparse.Namespace, where: str = "") -> DriverNames:
    from ur3hanoi.teach.driver import DriverNames

    if args.driver == "ur":
        from ur3hanoi.teach.ur_driver import ur_names

        return ur_names(where, args.via)
    if args.via == "ros":
        return DriverNames(where, "ur3/position", "ur3/command", "ros-solve")
    return DriverNames(where, "ur3e/position", "ur3e/command", "ros2-solve")


def _connect(args: argparse.Namespace, base: Station) -> tuple[Any, DriverNames]:
    """The connected arm of ``--via`` and how messages name it (DriverError: no driver within ``--wait``)."""
    print(f"ur3hanoi teach: looking for the driver (at most {args.wait:g} s) ...", flush=True)
    if args.driver == "ur":
        from ur3hanoi.cli.teach_ur import connect_ur

        return connect_ur(args, base)
    if args.via == "ros":
        from ur3hanoi.interface.ros1.client import ArmConfig, RosArm

        arm: Any = RosArm(ArmConfig(connect_timeout_s=args.wait), master_uri=args.master)
        where = arm.master_uri
    else:
        from ur3hanoi.errors import InputError
        from ur3hanoi.interface.ros2.client import Ros2Arm, Ros2ArmConfig
        from ur3hanoi.interface.ros2.dds import domain_id_from_env

        try:
            domain = domain_id_from_env() if args.domain_id is None else args.domain_id
        except ValueError as exc:
            raise InputError(str(exc)) from None
        arm = Ros2Arm(Ros2ArmConfig(connect_timeout_s=args.wait, convention=args.convention), domain, args.network)
        where = f"ROS_DOMAIN_ID {domain} ({args.network})"
    try:
        arm.connect()
    except BaseException:
        arm.close()
        raise
    return arm, _names(args, where)


def run(args: argparse.Namespace) -> int:
    from ur3hanoi.io.atomic import check_output
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.teach.taught_file import open_taught

    _check_options(args)
    base_file = input_file(args.base)
    out = Path(args.output)
    station_out = Path(args.station_out) if args.station_out else out.with_name(f"{out.stem}_station.yaml")
    check_output(out, inputs=[base_file])
    check_output(station_out, inputs=[base_file, out])
    if args.table is not None:
        check_output(args.table, inputs=[base_file, out, station_out])
    base = load_station(args.base)
    why = f"{base.name} has {base.n_towers} towers"
    check_number("--start", args.start, base.n_towers, "a tower", why)
    if args.record_now is not None:
        check_number("--record-now tower", args.record_now[0], base.n_towers, "a tower", why)
        check_number("--record-now height", args.record_now[1], base.n_heights, "a height",
                     f"{base.name} has {base.n_heights} heights")
    base_label = Path(args.base).as_posix()
    taught = open_taught(out, base, base_label, protected=(base_file,))
    if args.record_now is None and not args.finish and not sys.stdin.isatty():
        raise UsageError("stdin is not a terminal: teach is a session at the keyboard; in a script record a pose "
                         "with --record-now T,H (the published pose as tower T height H) and end with --finish")
    if args.record_now is not None or not args.finish:
        code, taught = _session(args, base, base_label, taught)
        if code != exit_codes.OK:
            return code
    if args.finish or args.record_now is None:
        _finish(args, base, base_label, taught, station_out)
    return exit_codes.OK


def _session(args: argparse.Namespace, base: Station, base_label: str, taught: TaughtFile) -> tuple[int, TaughtFile]:
    """Connect and record (one pose with ``--record-now``, else the terminal session): (exit code, the file)."""
    from ur3hanoi.errors import DriverError
    from ur3hanoi.teach.session import Teacher

    arm, names = _connect(args, base)
    teacher: Teacher | None = None
    try:
        accept = {(t - 1, h - 1) for t, h in args.accept or ()}
        if args.driver == "ur":
            from ur3hanoi.teach.ur_driver import UrTeacher

            teacher = UrTeacher(base, base_label, taught, arm, names, args.start - 1, accept)
        else:
            teacher = Teacher(base, base_label, taught, arm, names, args.start - 1, accept)
        if args.record_now is not None:
            _record_now(teacher, args.record_now, args.wait)
            return exit_codes.OK, teacher.taught
        return _interactive(teacher, names), teacher.taught
    except DriverError as exc:
        kept = teacher.taught if teacher is not None else taught
        raise DriverError(f"{exc}: {_saved(kept)}; run the same command again when the driver is back") from None
    finally:
        arm.close()


def _saved(taught: TaughtFile) -> str:
    n = len(taught.points)
    return (f"{shown(taught.path)} keeps its {n} point{'s' if n != 1 else ''}" if n else
            f"nothing was recorded in {shown(taught.path)}")


def _record_now(teacher: Any, slot_1: tuple[int, int], wait_s: float) -> None:
    import time

    from ur3hanoi.errors import Ur3HanoiError

    teacher.record_hint = "record it with --record-now TOWER,HEIGHT"
    teacher.name_extra(slot_1[0] - 1, slot_1[1] - 1)
    deadline = time.monotonic() + wait_s
    while True:
        ok, lines = teacher.record()
        if ok:
            print("\n".join(lines))
            return
        if time.monotonic() > deadline:
            raise Ur3HanoiError(f"{lines[-1]} (waited {wait_s:g} s for the arm to be still)")
        time.sleep(0.1)


def _interactive(teacher: Any, names: DriverNames) -> int:
    """The terminal session; the exit code (OK when finished with f)."""
    import os
    import signal

    from ur3hanoi.teach.interactive import run as run_session
    from ur3hanoi.teach.terminal import Keys, Screen, TerminalGoneError

    kind = ("ur3hanoi's simulated station, no pendant: jog with the keys" if teacher.simulated else
            "not ur3hanoi's station: move the arm with the pendant's freedrive")
    n = len(teacher.taught.points)
    cont = f"; continuing {shown(teacher.taught.path)}: {n} point(s) recorded" if n else ""
    print(f"connected to the driver on {names.where} ({kind}){cont}", flush=True)
    if hasattr(teacher.driver, "program_running"):
        from ur3hanoi.teach.ur_driver import program_line

        print(program_line(teacher.driver), flush=True)
    try:
        with Keys() as keys:
            run_session(teacher, keys, Screen())
    except KeyboardInterrupt:
        print(f"\nur3hanoi teach: stopped: {_saved(teacher.taught)}; run the same command to continue",
              file=sys.stderr)
        return exit_codes.INTERRUPTED
    except TerminalGoneError as exc:
        if exc.hangup:  # nobody to tell: keep quiet (writing to a closed terminal fails), and stay so
            signal.signal(signal.SIGHUP, signal.SIG_IGN)
            devnull = os.open(os.devnull, os.O_WRONLY)
            os.dup2(devnull, 1)
            os.dup2(devnull, 2)
            return HANGUP
        print(f"ur3hanoi teach: {exc}: {_saved(teacher.taught)}", file=sys.stderr)
        return TERMINATED
    return exit_codes.OK


def _finish(args: argparse.Namespace, base: Station, base_label: str, taught: TaughtFile, station_out: Path) -> None:
    """Fit, print the audit, write the calibration and the table key, say how accurate it is and what to run."""
    from ur3hanoi.audit import audit_taught
    from ur3hanoi.calibrate import fit_station, write_calibration
    from ur3hanoi.calibrate.verdict import note_lines
    from ur3hanoi.cli.tables import write_key
    from ur3hanoi.errors import TaughtPointsError
    from ur3hanoi.teach.feedback import BY_POINTS, feedback

    if not taught.points:
        raise TaughtPointsError(f"{shown(taught.path)}: no point recorded yet: nothing to calibrate",
                                source=str(taught.path))
    points = taught.taught()
    accept = check_accept(args.accept, {(p.tower, p.height) for p in points.points if p.k == 0},
                          taught.path.as_posix())
    fit = fit_station(base, points, name=shown(station_out.stem)[:255], source=str(station_out), accept=accept)
    print(audit_taught(fit, points).text())
    write_calibration(station_out, fit, points, base, taught_label=taught.path.as_posix(), base_label=base_label,
                      inputs=[input_file(args.base), taught.path])
    for line in note_lines(fit.points, fit.accepted, fit.single_pose, base_label):
        print(line)
    fb = feedback(base, points, base_label, accept)
    checked = [r.off_mm for r in fb.rows if r.by == BY_POINTS and not math.isnan(r.off_mm) and fit.used[r.index]]
    exact = ("an exact fit (one point per tower): each tower origin is where its taught pose put it, as accurate "
             "as that pose" if fit.dof == 0 else f"residual rms {fit.rms_mm:.2f} mm over {fit.n_used} points")
    within = (f"every point the others check within {max(checked):.1f} mm of where they put it" if checked else
              "no point is checked by the others")
    print(f"wrote {shown(station_out)}: {exact}; {within}; {len(fit.suspects)} suspect(s)")
    key = args.key or "real_pos"
    if args.table is not None:
        print(write_key(str(station_out), key, args.table))
    slowly = ("the pendant's speed slider at 25 %" if args.driver == "ur" else "an eighth of the lab's speed")
    print(f"next, slowly ({slowly}; watch it, a hand on the stop button): "
          f"{_next_command(args, station_out, key, base.n_towers)}")


def _next_command(args: argparse.Namespace, station_out: Path, key: str, n_towers: int) -> str:
    """The first solve to try on the new table: from the blocks' tower to the last one (the first, from the last)."""
    import shlex

    start = args.start
    end = n_towers if start != n_towers else 1
    cmd = ["ur3hanoi", _names(args).solve] + (["--driver", "ur"] if args.driver == "ur" else [])
    if args.table is not None:
        cmd += ["--table", args.table, "--key", key]
    cmd += ["--calibration", station_out.as_posix(), "--start", str(start), "--end", str(end)]
    cmd += ["--v", f"{FIRST_SOLVE_SPEED:g}", "--a", f"{FIRST_SOLVE_SPEED:g}"] if args.driver == "course" else []
    if args.via == "ros" and args.master:
        cmd += ["--master", args.master]
    if args.via == "ros2" and args.driver == "ur":
        cmd += [] if args.ros_distro is None else ["--ros-distro", args.ros_distro]
        cmd += [] if args.network == "loopback" else ["--network", args.network]
        cmd += [] if args.domain_id is None else ["--domain-id", str(args.domain_id)]
    elif args.via == "ros2":
        cmd += [] if args.convention == "course" else ["--convention", args.convention]
        cmd += [] if args.network == "loopback" else ["--network", args.network]
        cmd += [] if args.domain_id is None else ["--domain-id", str(args.domain_id)]
    return shlex.join(cmd)
