"""The ROS subcommands of ``ur3hanoi``: ``ros-station``, ``ros-solve`` and ``ros-env``.

:func:`add` adds them to the main parser's subparsers. Conventions as in the other subcommands (numeric ranges
in :mod:`ur3hanoi.cli.options`): towers, heights, blocks and grasps numbered from 1; ``--calibration`` takes a shipped
station name (``lab_sim``) or a file; errors are one line ``ur3hanoi: error: ...`` with exit code 2, a suction
fault exits with 3. Heavy imports (MuJoCo, rospy) happen only when a command runs.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from ur3hanoi.cli.common import DEFAULT_CALIBRATION, add_suction_profile_option
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
    check_number,
    option,
    station_number,
)
from ur3hanoi.cli.solve import prompt_tower


def _master_help() -> str:
    return "ROS master URI (default: $ROS_MASTER_URI, else http://localhost:11311)"


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``ros-station``, ``ros-solve`` and ``ros-env`` to ``sub``."""
    _add_station(sub)
    _add_solve(sub)
    _add_env(sub)


# ------------------------------------------------------------------------------------------------ ros-station


def _add_station(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ros-station", help="run the MuJoCo station as the course's ROS driver (ur3/command, position, gripper_input)",
        description="A drop-in for the course's Gazebo world and ur3_driver: executes ur3/command as the UR "
                    "controller's movej (v and a capped at the UR3 limits: 180 deg/s joints 1-3, 360 deg/s wrists, "
                    "4/8 rad/s^2), switches suction with io_0, publishes ur3/position and ur3/gripper_input at "
                    "--rate in real time. Topics ur3hanoi/spawn (std_msgs/Int32 tower) and ur3hanoi/remove_block "
                    "(block, 1 = bottom) respawn and remove blocks. Starts a roscore when none answers (stopped "
                    "with the station, even when it is killed). Listens on 127.0.0.1 only unless --host. Refuses "
                    "moves longer than 60 s and more than 100 waiting commands; logs at most one line per topic "
                    "and second. On SIGINT/SIGTERM (and SIGUSR1, without stopping) writes a JSON report to "
                    "--report or stdout; everything else goes to stderr.")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML or shipped name (default {DEFAULT_CALIBRATION})")
    p.add_argument("--start", type=station_number("a tower"), default=1, metavar="T",
                   help="tower the blocks are spawned on (default 1)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N",
                   help="number of blocks (default: the grid's)")
    p.add_argument("--remove-block", type=option(HEIGHT), metavar="H",
                   help="fault injection: spawn without the block at height H, like lab2_spawn.py")
    p.add_argument("--drop-on-grasp", type=option(MOVE), metavar="K",
                   help="fault injection: the block of the K-th grasp falls off during the next motion")
    p.add_argument("--seed", type=option(SEED), default=0, metavar="K", help="seed of the AIN0 noise")
    p.add_argument("--rate", type=option(ROS_RATE), default=125.0, metavar="HZ",
                   help="control and publishing rate, 50..500 Hz, period a multiple of 2 ms (default 125, CB3)")
    p.add_argument("--report", metavar="FILE", help="write the JSON report to FILE (default: stdout)")
    p.add_argument("--duration", type=option(DURATION), metavar="S", help="stop by itself after S seconds")
    p.add_argument("--master", metavar="URI", help=_master_help())
    p.add_argument("--host", metavar="ADDR", default="127.0.0.1",
                   help="address the station and the roscore it starts listen on and advertise (ROS_IP); default "
                        "127.0.0.1: this machine only. Give this machine's lab-network address to open them to "
                        "other machines (a master on another machine needs it)")
    add_suction_profile_option(p)
    out = p.add_mutually_exclusive_group()
    out.add_argument("--video", metavar="FILE.mp4", help="render an MP4 offscreen (headless: MUJOCO_GL=egl)")
    out.add_argument("--frames", metavar="DIR", help="render PNG frames offscreen into DIR")
    p.set_defaults(func=_run_station)


def _run_station(args: argparse.Namespace) -> int:
    if (args.video or args.frames) and "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"  # headless offscreen rendering (read when the GL context is created)
    from ur3hanoi.cli.common import check_render_outputs, input_file
    from ur3hanoi.io.atomic import check_output
    from ur3hanoi.ros.station import RosStation, StationOptions

    inputs = [input_file(args.calibration or DEFAULT_CALIBRATION)]
    report_file = None if args.report in (None, "-") else Path(args.report)  # "-": standard output
    if report_file is not None:
        check_output(report_file, inputs=inputs)  # before any work
    check_render_outputs(args.video, args.frames, inputs)
    options = StationOptions(
        calibration=args.calibration or DEFAULT_CALIBRATION, start=args.start - 1, n_blocks=args.blocks,
        removed=None if args.remove_block is None else args.remove_block - 1,
        drop_on_grasp=None if args.drop_on_grasp is None else args.drop_on_grasp - 1, seed=args.seed,
        rate_hz=args.rate, report=report_file,
        frames=Path(args.frames) if args.frames else None, video=Path(args.video) if args.video else None,
        duration_s=args.duration, master_uri=args.master, host=args.host,
        suction_profile=args.suction_profile)
    node = RosStation(options)
    # Standard output carries only the JSON report: whatever else writes to file descriptor 1 (rospy's info
    # handler, C libraries) goes to stderr while the node runs.
    sys.stdout.flush()
    report_fd = os.dup(1)
    os.dup2(2, 1)
    try:
        with os.fdopen(os.dup(report_fd), "w") as report_out:
            node.report_out = lambda text: print(text, file=report_out, flush=True)
            report = node.run()
    finally:
        sys.stdout.flush()
        os.dup2(report_fd, 1)
        os.close(report_fd)
    if report_file is not None:
        c, ctl = report["commands"], report["control"]
        blocks = ", ".join(f"{b['block']} " + ("off-grid" if b["tower"] is None else
                                              f"tower {b['tower']} height {b['height']}")
                           for b in report["final"]["blocks"])
        print(f"ros-station stopped: {c['executed']} commands executed, {c['rejected']} refused; blocks {blocks}; "
              f"worst loop lag {1e3 * ctl['worst_lag_s']:.2f} ms; report {args.report}", file=sys.stderr, flush=True)
    return 0


# -------------------------------------------------------------------------------------------------- ros-solve


def _add_solve(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ros-solve", help="solve the puzzle through ur3/command like the lab program (ros-station or the real UR3)",
        description="The lab program, done right: moves every block through the course's ROS interface with a "
                    "waypoint table (--table FILE --key sim_pos|real_pos, or generated from --calibration), checks "
                    "the suction feedback (DIGIN bit 0) after every grasp and during every carry, and on a missing "
                    "or dropped block halts like the lab asks: suction off, arm home, error, exit 3. Without "
                    "--start/--end it prompts like the lab program. Towers are numbered from 1.")
    p.add_argument("--start", type=station_number("a tower"), metavar="S", help="start tower (1-based)")
    p.add_argument("--end", type=station_number("a tower"), metavar="E", help="destination tower (1-based)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N",
                   help="number of blocks (default: the table's)")
    p.add_argument("--table", metavar="FILE", help="lab-format table (lab2_data.yaml); default: IK of --calibration")
    p.add_argument("--key", default=None, choices=["sim_pos", "real_pos"], help="table key (default sim_pos)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration: the table's source without --table, and the home pose "
                        f"(default {DEFAULT_CALIBRATION}; with --table and no --calibration: the lab's home)")
    p.add_argument("--v", type=option(CMD_SPEED), default=4.0, metavar="V",
                   help="joint speed sent with each command [rad/s] (default 4.0, the lab's; capped by the driver)")
    p.add_argument("--a", type=option(CMD_ACCELERATION), default=4.0, metavar="A",
                   help="joint acceleration sent with each command [rad/s^2] (default 4.0, the lab's)")
    p.add_argument("--grasp-timeout", type=option(GRASP_TIMEOUT), default=1.0, metavar="S",
                   help="wait at most S seconds for the vacuum switch after suction on (default 1)")
    p.add_argument("--master", metavar="URI", help=_master_help())
    p.add_argument("--json", action="store_true", help="print one JSON object with the outcome on stdout")
    p.set_defaults(func=_run_solve)


def _run_solve(args: argparse.Namespace) -> int:
    import json

    import numpy as np

    from ur3hanoi.errors import SuctionFaultError
    from ur3hanoi.hanoi import validate_instance
    from ur3hanoi.labfile import read_recorded_table
    from ur3hanoi.robot import Q_HOME_LAB
    from ur3hanoi.ros.client import ArmConfig, RosArm
    from ur3hanoi.remote.solve import LabSolveConfig, run_lab_solve
    from ur3hanoi.station import load_station
    from ur3hanoi.waypoints import generate_table

    if args.table is None and args.key is not None:
        raise UsageError("--key is only used with --table (the table is generated from --calibration otherwise)")
    station = None if args.table is not None and args.calibration is None else \
        load_station(args.calibration or DEFAULT_CALIBRATION)
    if args.table is not None:  # the reader and the entry rule of `solve --table` (entries never visited may miss)
        recorded = read_recorded_table(args.table, args.key or "sim_pos")
        Q = recorded.q
    else:
        assert station is not None
        recorded, Q = None, generate_table(station).q
    home = np.array(Q_HOME_LAB if station is None else station.q_home, dtype=float)
    n_towers, n_heights = Q.shape[0], Q.shape[1]
    n_blocks = n_heights if args.blocks is None else args.blocks
    why = f"{station.name} has {n_towers} towers" if station is not None else f"the table has {n_towers} towers"
    check_number("--start", args.start, n_towers, "a tower", why)
    check_number("--end", args.end, n_towers, "a tower", why)
    if args.start is None or args.end is None:
        if not sys.stdin.isatty():
            raise UsageError("--start and --end are required when stdin is not a terminal "
                                f"(towers 1..{n_towers}), e.g. ur3hanoi ros-solve --start 1 --end 3")
        start = args.start - 1 if args.start is not None else prompt_tower("start", n_towers)
        end = args.end - 1 if args.end is not None else prompt_tower("end", n_towers, exclude=start)
    else:
        start, end = args.start - 1, args.end - 1
    validate_instance(n_blocks, start, end, n_towers, n_heights)
    if recorded is not None:
        Q = recorded.for_solve(start, end, n_blocks)

    say = (lambda s: print(s, file=sys.stderr, flush=True)) if args.json else (lambda s: print(s, flush=True))
    arm = RosArm(ArmConfig(v=args.v, a=args.a), master_uri=args.master, log=say)
    outcome: dict[str, object] = {"start": start + 1, "end": end + 1, "blocks": n_blocks, "v": args.v, "a": args.a}
    try:
        arm.connect()
        say(f"connected to {arm.master_uri}: {n_blocks} blocks, tower {start + 1} -> {end + 1}")
        try:
            result = run_lab_solve(arm, Q, home, start, end, n_blocks, LabSolveConfig(args.grasp_timeout), log=say)
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
        print(f"solved: {len(result.moves)} moves, tower {start + 1} -> {end + 1}, {arm.commands_sent} commands in "
              f"{result.wall_time_s:.1f} s")
    return 0


# ---------------------------------------------------------------------------------------------------- ros-env


def _add_env(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ros-env", help="write the ur3_driver messages for lab programs and print the environment to source",
        description="Write the course's ur3_driver message package (generated by genpy, the course's md5sums) and "
                    "a sitecustomize.py that appends Debian's ROS 1 Python folder into DIR, then print the export "
                    "lines for ROS_MASTER_URI and PYTHONPATH. Use: eval \"$(ur3hanoi ros-env)\"; then "
                    "`python lab2_exec.py --simulator True` runs against ros-station without a catkin workspace.")
    p.add_argument("--dir", metavar="DIR", help="folder to write (default: $XDG_CACHE_HOME/ur3hanoi/ros)")
    p.add_argument("--master", metavar="URI", help=_master_help())
    p.set_defaults(func=_run_env)


def _run_env(args: argparse.Namespace) -> int:
    from ur3hanoi.ros.env import default_cache_dir, env_lines
    from ur3hanoi.ros.master import MasterUri, master_uri_from_env
    from ur3hanoi.ros.msgs import write_client_env

    folder = Path(args.dir).resolve() if args.dir else default_cache_dir()
    uri = args.master or master_uri_from_env()
    MasterUri.parse(uri)
    files = write_client_env(folder)
    print(f"# ur3hanoi ros-env: wrote {len(files)} files (ur3_driver messages) to {folder}", file=sys.stderr)
    for line in env_lines(folder, uri):
        print(line)
    return 0
