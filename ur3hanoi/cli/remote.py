"""What the station and solve subcommands of both middlewares share (:mod:`ur3hanoi.cli.ros`,
:mod:`ur3hanoi.cli.ros2`): their common options, the station options they build, the "stopped" line, and the
solve's table, towers, outcome and exit handling around a connected arm (:mod:`ur3hanoi.interface`).

Conventions as in the other subcommands: towers, heights, blocks and grasps numbered from 1; errors one line with
exit code 2; a suction fault exits with 3 (after printing the ``--json`` outcome).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from ur3hanoi.cli.common import add_suction_profile_option
from ur3hanoi.cli.options import (
    BLOCKS,
    CMD_ACCELERATION,
    CMD_SPEED,
    DURATION,
    GRASP_TIMEOUT,
    HEIGHT,
    MOVE,
    ROS_RATE,
    SEED,
    UsageError,
    option,
    station_number,
)
from ur3hanoi.cli.prompt import towers

if TYPE_CHECKING:
    from ur3hanoi.arrays import FloatArray

# --------------------------------------------------------------------------------------------------- stations


def station_parser(sub: argparse._SubParsersAction, name: str, summary: str, description: str,
                   default_calibration: str, analog: str, rate_note: str = "") -> argparse.ArgumentParser:
    """The ``name`` station subcommand with ``--calibration`` .. ``--rate`` (:func:`add_station_options`)."""
    p: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=description)
    add_station_options(p, default_calibration, analog, rate_note)
    return p


def add_station_options(p: argparse.ArgumentParser, default_calibration: str, analog: str, rate_note: str = ""
                        ) -> None:
    """``--calibration`` .. ``--rate``: the station, its blocks, fault injection, noise seed (of ``analog``);
    ``rate_note`` follows the rate's default in the help."""
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML or shipped name (default {default_calibration})")
    p.add_argument("--start", type=station_number("a tower"), default=1, metavar="T",
                   help="tower the blocks are spawned on (default 1)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N",
                   help="number of blocks (default: the grid's)")
    p.add_argument("--remove-block", type=option(HEIGHT), metavar="H",
                   help="fault injection: spawn without the block at height H, like lab2_spawn.py")
    p.add_argument("--drop-on-grasp", type=option(MOVE), metavar="K",
                   help="fault injection: the block of the K-th grasp falls off during the next motion")
    p.add_argument("--seed", type=option(SEED), default=0, metavar="K", help=f"seed of the {analog} noise")
    p.add_argument("--rate", type=option(ROS_RATE), default=None, metavar="HZ",
                   help=f"control and publishing rate, 50..500 Hz, period a multiple of 2 ms (default 125{rate_note}; "
                        "with --driver ur the robot's control rate: 125 on a UR3, 500 on a UR3e)")


def add_station_outputs(p: argparse.ArgumentParser) -> None:
    """``--report``, ``--duration``, ``--suction-profile``, ``--video``/``--frames`` (one of them)."""
    p.add_argument("--report", metavar="FILE", help="write the JSON report to FILE (default: stdout)")
    p.add_argument("--duration", type=option(DURATION), metavar="S", help="stop by itself after S seconds")
    add_suction_profile_option(p)
    out = p.add_mutually_exclusive_group()
    out.add_argument("--video", metavar="FILE.mp4",
                     help="render an MP4 offscreen (OpenGL: the display's, else EGL, else OSMesa, or MUJOCO_GL)")
    out.add_argument("--frames", metavar="DIR", help="render PNG frames offscreen into DIR (OpenGL as --video)")


def check_station_outputs(args: argparse.Namespace, default_calibration: str) -> Path | None:
    """Refuse a ``--report``, ``--video`` or ``--frames`` that cannot be written (:mod:`ur3hanoi.io.atomic`), before
    any work; returns the report file (None: standard output, also for ``--report -``). With ``--video`` or
    ``--frames``, chooses the OpenGL platform the rendering process will use (it inherits ``MUJOCO_GL``) and says
    which on stderr."""
    from ur3hanoi.cli.common import check_render_outputs, input_file
    from ur3hanoi.io.atomic import check_output

    inputs = [input_file(args.calibration or default_calibration)]
    report = None if args.report in (None, "-") else Path(args.report)
    if report is not None:
        check_output(report, inputs=inputs)
    gl = check_render_outputs(args.video, args.frames, inputs)
    if gl is not None:
        print(f"ur3hanoi {args.command}: rendering with {gl.describe()}", file=sys.stderr, flush=True)
    return report


def station_options(args: argparse.Namespace, default_calibration: str, report: Path | None) -> dict[str, Any]:
    """The :class:`ur3hanoi.interface.common.station.ServerOptions` fields of the common options (numbers from 0)."""
    return {"calibration": args.calibration or default_calibration, "start": args.start - 1,
            "n_blocks": args.blocks, "removed": None if args.remove_block is None else args.remove_block - 1,
            "drop_on_grasp": None if args.drop_on_grasp is None else args.drop_on_grasp - 1, "seed": args.seed,
            "rate_hz": args.rate if args.rate is not None or getattr(args, "driver", "course") == "ur" else 125.0,
            "report": report, "duration_s": args.duration,
            "suction_profile": args.suction_profile, "frames": Path(args.frames) if args.frames else None,
            "video": Path(args.video) if args.video else None}


class ReportStdout:
    """Standard output for a station's JSON report alone (``station > report.json`` is JSON): inside, whatever
    else writes to file descriptor 1 (rospy's info handler, DDS and other C libraries, child processes) goes to
    stderr; the value of ``with`` prints a report to the real stdout."""

    def __enter__(self) -> Callable[[str], None]:
        import os

        sys.stdout.flush()
        self._fd = os.dup(1)
        os.dup2(2, 1)
        self._file = os.fdopen(os.dup(self._fd), "w")
        return lambda text: print(text, file=self._file, flush=True)

    def __exit__(self, *exc: object) -> None:
        import os

        try:
            self._file.close()
        finally:
            sys.stdout.flush()
            os.dup2(self._fd, 1)
            os.close(self._fd)


def stopped_line(command: str, report: dict[str, Any], extra: str = "") -> str:
    """``COMMAND stopped: N commands executed, M refused; EXTRA`` (``extra`` ends with the report file); with the
    UR driver's interface ``N goals accepted, M rejected``."""
    if "goals" in report:
        g = report["goals"]
        return f"{command} stopped: {g['accepted']} goals accepted, {g['rejected']} rejected; {extra}"
    c = report["commands"]
    return f"{command} stopped: {c['executed']} commands executed, {c['rejected']} refused; {extra}"


# ------------------------------------------------------------------------------------------------------ solve


def solve_parser(sub: argparse._SubParsersAction, name: str, summary: str, description: str,
                 calibration_help: str, speed_notes: tuple[str, str], default_speed: float) -> argparse.ArgumentParser:
    """The ``name`` solve subcommand with :func:`add_solve_options` and ``--calibration``."""
    p: argparse.ArgumentParser = sub.add_parser(name, help=summary, description=description)
    add_solve_options(p, speed_notes, default_speed)
    p.add_argument("--calibration", default=None, metavar="CAL", help=calibration_help)
    return p


def add_solve_options(p: argparse.ArgumentParser, speed_notes: tuple[str, str], default_speed: float) -> None:
    """``--start`` .. ``--key``, ``--v``/``--a`` (``speed_notes`` follow their defaults in the help),
    ``--grasp-timeout`` (``--calibration`` is the binding's)."""
    p.add_argument("--start", type=station_number("a tower"), metavar="S", help="start tower (1-based)")
    p.add_argument("--end", type=station_number("a tower"), metavar="E", help="destination tower (1-based)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N",
                   help="number of blocks (default: the table's)")
    p.add_argument("--table", metavar="FILE", help="lab-format table (lab2_data.yaml, controller convention); "
                                                   "default: IK of --calibration")
    p.add_argument("--key", default=None, choices=["sim_pos", "real_pos"], help="table key (default sim_pos)")
    p.add_argument("--v", type=option(CMD_SPEED), default=default_speed, metavar="V",
                   help=f"joint speed sent with each command [rad/s] (default {default_speed:.1f}{speed_notes[0]})")
    p.add_argument("--a", type=option(CMD_ACCELERATION), default=default_speed, metavar="A",
                   help=f"joint acceleration sent with each command [rad/s^2] (default {default_speed:.1f}"
                        f"{speed_notes[1]})")
    p.add_argument("--grasp-timeout", type=option(GRASP_TIMEOUT), default=1.0, metavar="S",
                   help="wait at most S seconds for the vacuum switch after suction on (default 1)")


def add_json_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--json", action="store_true", help="print one JSON object with the outcome on stdout")


class SolveJob(NamedTuple):
    """What a solve subcommand runs: the table ``Q`` [rad, controller convention], the home pose [rad], towers
    (0-based) and the number of blocks. (A NamedTuple, not a frozen dataclass: this module builds the ``ros-*``
    parsers, and importing dataclasses would cost every ``--help`` 8-10 ms.)"""

    Q: FloatArray
    home: FloatArray
    start: int
    end: int
    n_blocks: int


def solve_job(args: argparse.Namespace, command: str, default_calibration: str, station_optional: bool) -> SolveJob:
    """The table (``--table``/``--key`` or generated from ``--calibration``), home, towers (prompted on a terminal
    when missing) and blocks, checked. With ``station_optional``, ``--table`` without ``--calibration`` uses no
    station (the lab's home)."""
    import numpy as np

    from ur3hanoi.hanoi import validate_instance
    from ur3hanoi.robot.model import Q_HOME_LAB
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.tables import read_recorded_table
    from ur3hanoi.tables.ik_table import generate_table

    if args.table is None and args.key is not None:
        raise UsageError("--key is only used with --table (the table is generated from --calibration otherwise)")
    station = None if station_optional and args.table is not None and args.calibration is None else \
        load_station(args.calibration or default_calibration)
    # The reader and the entry rule of `solve --table` (entries never visited may miss).
    recorded = read_recorded_table(args.table, args.key or "sim_pos") if args.table is not None else None
    if recorded is not None:
        Q = recorded.q
    else:
        assert station is not None
        Q = generate_table(station).q
    home = np.array(Q_HOME_LAB if station is None else station.q_home, dtype=float)
    n_towers, n_heights = Q.shape[0], Q.shape[1]
    n_blocks = n_heights if args.blocks is None else args.blocks
    why = f"{station.name} has {n_towers} towers" if station is not None else f"the table has {n_towers} towers"
    start, end = towers(args, n_towers, why, command)
    validate_instance(n_blocks, start, end, n_towers, n_heights)
    if recorded is not None:
        Q = recorded.for_solve(start, end, n_blocks)
    return SolveJob(Q, home, start, end, n_blocks)


def say_for(args: argparse.Namespace) -> Callable[[str], None]:
    """Where progress lines go: stdout, or stderr with ``--json`` (stdout carries only the outcome)."""
    if args.json:
        return lambda s: print(s, file=sys.stderr, flush=True)
    return lambda s: print(s, flush=True)


def drive(args: argparse.Namespace, arm: Any, job: SolveJob, connected: str,
          outcome: dict[str, object]) -> int:
    """Connect ``arm`` (a :class:`ur3hanoi.interface.course.client.TopicArm`), say ``connected``, run the lab's solve,
    close the arm; print the outcome (one JSON object with ``--json``). A suction fault is re-raised (exit 3)
    after its outcome is printed."""
    import json

    from ur3hanoi.errors import SuctionFaultError
    from ur3hanoi.interface.course.solve import LabSolveConfig, run_lab_solve

    say = say_for(args)
    try:
        arm.connect()
        say(connected)
        try:
            result = run_lab_solve(arm, job.Q, job.home, job.start, job.end, job.n_blocks,
                                   LabSolveConfig(args.grasp_timeout), log=say)
        except SuctionFaultError as exc:
            outcome.update(status="halted", exit_code=exc.exit_code, error=str(exc), commands=arm.commands_sent)
            if args.json:
                print(json.dumps(outcome))
            raise
    finally:
        arm.close()
    outcome.update(status="solved", exit_code=0, moves=len(result.moves), wall_time_s=round(result.wall_time_s, 3),
                   commands=arm.commands_sent)
    if args.json:
        print(json.dumps(outcome))
    else:
        print(f"solved: {len(result.moves)} moves, tower {job.start + 1} -> {job.end + 1}, {arm.commands_sent} "
              f"commands in {result.wall_time_s:.1f} s")
    return 0
