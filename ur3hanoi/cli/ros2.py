"""The ROS 2 subcommands of ``ur3hanoi``: ``ros2-station`` and ``ros2-solve`` (no ROS installation: Cyclone DDS).

Conventions as in :mod:`ur3hanoi.cli.ros`: towers, heights, blocks and grasps numbered from 1; errors one line with
exit code 2; a suction fault exits with 3. Heavy imports (MuJoCo, Cyclone DDS) happen only when a command runs.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

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
    check_number,
    option,
    station_number,
)
from ur3hanoi.cli.solve import prompt_tower

DEFAULT_ROS2_CALIBRATION = "ur3e_sim"
_DOMAIN_HELP = "ROS_DOMAIN_ID, 0..232 (default: $ROS_DOMAIN_ID, else 0)"
_NETWORK_HELP = ("DDS network: loopback (default: nothing leaves this machine), lab (join the lab network: "
                 "Cyclone's interface choice, multicast discovery) or a network interface name")


def _domain(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected an integer in [0, 232]") from None
    if not 0 <= value <= 232:
        raise argparse.ArgumentTypeError(f"invalid value {value}: expected an integer in [0, 232]")
    return value


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``ros2-station`` and ``ros2-solve`` to ``sub``."""
    _add_station(sub)
    _add_solve(sub)


def _add_station(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ros2-station", help="run the MuJoCo station as the ROS 2 course bridge (ur3e/command, position, "
                             "gripper_input) without ROS",
        description="The ROS 2 course bridge (UMD ENME480 ur3e_mrc_msgs) over Cyclone DDS, no ROS installation: "
                    "subscribes ur3e/command (CommandUR3e), publishes ur3e/position (PositionUR3e), "
                    "ur3e/gripper_input (GripperInput: the suction model's dig_in/a_in0) and gripper/grasping "
                    "(Bool), default QoS, node ur3hanoi_station. Bridge behaviour by default: destinations of "
                    "length != 6 dropped with a log line, every move 2 s (v and a ignored), is_ready always true, "
                    "joint values in the bridge's convention (controller = course + [pi/2, 0, 0, -pi/2, 0, 0]). "
                    "Loopback only unless --network. On SIGINT/SIGTERM (SIGUSR1: without stopping) writes a JSON "
                    "report to --report or stdout.")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML or shipped name (default {DEFAULT_ROS2_CALIBRATION})")
    p.add_argument("--start", type=station_number("a tower"), default=1, metavar="T",
                   help="tower the blocks start on (default 1)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N", help="number of blocks (default: all)")
    p.add_argument("--remove-block", type=option(HEIGHT), metavar="H",
                   help="fault injection: spawn without the block at height H")
    p.add_argument("--drop-on-grasp", type=option(MOVE), metavar="K",
                   help="fault injection: the block of the K-th grasp falls off during the next motion")
    p.add_argument("--seed", type=option(SEED), default=0, metavar="K", help="seed of the a_in0 noise")
    p.add_argument("--rate", type=option(ROS_RATE), default=125.0, metavar="HZ",
                   help="control and publishing rate, 50..500 Hz, period a multiple of 2 ms (default 125)")
    p.add_argument("--timing", choices=["bridge", "honest"], default="bridge",
                   help="bridge: fixed 2 s moves, is_ready always true (default); honest: the controller's movej at "
                        "the message's v and a, is_ready = arrived")
    p.add_argument("--convention", choices=["course", "controller"], default="course",
                   help="joint convention on the topics (default course, the bridge's)")
    p.add_argument("--network", default="loopback", metavar="NET", help=_NETWORK_HELP)
    p.add_argument("--domain-id", type=_domain, default=None, metavar="ID", help=_DOMAIN_HELP)
    p.add_argument("--report", metavar="FILE", help="write the JSON report to FILE (default: stdout)")
    p.add_argument("--duration", type=option(DURATION), metavar="S", help="stop by itself after S seconds")
    add_suction_profile_option(p)
    p.set_defaults(func=_run_station)


def _run_station(args: argparse.Namespace) -> int:
    from ur3hanoi.ros2.station import Ros2Station, Ros2StationOptions

    options = Ros2StationOptions(
        calibration=args.calibration or DEFAULT_ROS2_CALIBRATION, start=args.start - 1, n_blocks=args.blocks,
        removed=None if args.remove_block is None else args.remove_block - 1,
        drop_on_grasp=None if args.drop_on_grasp is None else args.drop_on_grasp - 1, seed=args.seed,
        rate_hz=args.rate, report=Path(args.report) if args.report else None, duration_s=args.duration,
        timing=args.timing, convention=args.convention, network=args.network, domain_id=args.domain_id,
        suction_profile=args.suction_profile)
    report = Ros2Station(options).run()
    if args.report:
        c = report["commands"]
        print(f"ros2-station stopped: {c['executed']} commands executed, {c['rejected']} refused; report "
              f"{args.report}", flush=True)
    return 0


def _add_solve(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "ros2-solve", help="solve the puzzle through ur3e/command (ros2-station or the course's UR3e bridge)",
        description="ros-solve over the ROS 2 course interface: moves every block with a waypoint table "
                    "(--table FILE --key, controller convention, or generated from --calibration), waits until "
                    "every joint is within 0.0008 rad, checks dig_in bit 0 after every grasp and during every "
                    "carry, and on a missing or dropped block halts: suction off, arm home, error, exit 3.")
    p.add_argument("--start", type=station_number("a tower"), metavar="S", help="start tower (1-based)")
    p.add_argument("--end", type=station_number("a tower"), metavar="E", help="destination tower (1-based)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N", help="number of blocks")
    p.add_argument("--table", metavar="FILE", help="lab-format table (controller convention); default: IK of "
                                                   "--calibration")
    p.add_argument("--key", default=None, choices=["sim_pos", "real_pos"], help="table key (default sim_pos)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration: the table's source and the home pose (default "
                        f"{DEFAULT_ROS2_CALIBRATION})")
    p.add_argument("--v", type=option(CMD_SPEED), default=1.0, metavar="V",
                   help="joint speed sent with each command [rad/s] (default 1.0; the course bridge ignores it)")
    p.add_argument("--a", type=option(CMD_ACCELERATION), default=1.0, metavar="A",
                   help="joint acceleration sent with each command [rad/s^2] (default 1.0; ignored by the bridge)")
    p.add_argument("--grasp-timeout", type=option(GRASP_TIMEOUT), default=1.0, metavar="S",
                   help="wait at most S seconds for the vacuum switch after suction on (default 1)")
    p.add_argument("--convention", choices=["course", "controller"], default="course",
                   help="joint convention on the topics (default course, the bridge's)")
    p.add_argument("--network", default="loopback", metavar="NET", help=_NETWORK_HELP)
    p.add_argument("--domain-id", type=_domain, default=None, metavar="ID", help=_DOMAIN_HELP)
    p.add_argument("--json", action="store_true", help="print one JSON object with the outcome on stdout")
    p.set_defaults(func=_run_solve)


def _run_solve(args: argparse.Namespace) -> int:
    import numpy as np

    from ur3hanoi.errors import SuctionFaultError
    from ur3hanoi.hanoi import validate_instance
    from ur3hanoi.labfile import read_recorded_table
    from ur3hanoi.remote.errors import RosError
    from ur3hanoi.remote.solve import LabSolveConfig, run_lab_solve
    from ur3hanoi.ros2.client import Ros2Arm, Ros2ArmConfig
    from ur3hanoi.ros2.dds import domain_id_from_env
    from ur3hanoi.station import load_station
    from ur3hanoi.waypoints import generate_table

    if args.table is None and args.key is not None:
        raise UsageError("--key is only used with --table (the table is generated from --calibration otherwise)")
    station = load_station(args.calibration or DEFAULT_ROS2_CALIBRATION)
    # The reader and the entry rule of `solve --table` and `ros-solve --table` (entries never visited may miss).
    recorded = read_recorded_table(args.table, args.key or "sim_pos") if args.table is not None else None
    Q = recorded.q if recorded is not None else generate_table(station).q
    home = np.array(station.q_home, dtype=float)
    n_towers, n_heights = Q.shape[0], Q.shape[1]
    n_blocks = n_heights if args.blocks is None else args.blocks
    why = f"{station.name} has {n_towers} towers"
    check_number("--start", args.start, n_towers, "a tower", why)
    check_number("--end", args.end, n_towers, "a tower", why)
    if args.start is None or args.end is None:
        if not sys.stdin.isatty():
            raise UsageError("--start and --end are required when stdin is not a terminal "
                             f"(towers 1..{n_towers}), e.g. ur3hanoi ros2-solve --start 1 --end 3")
        start = args.start - 1 if args.start is not None else prompt_tower("start", n_towers)
        end = args.end - 1 if args.end is not None else prompt_tower("end", n_towers, exclude=start)
    else:
        start, end = args.start - 1, args.end - 1
    validate_instance(n_blocks, start, end, n_towers, n_heights)
    if recorded is not None:
        Q = recorded.for_solve(start, end, n_blocks)
    try:
        domain = domain_id_from_env() if args.domain_id is None else args.domain_id
    except ValueError as exc:
        raise RosError(str(exc)) from None

    say = (lambda s: print(s, file=sys.stderr, flush=True)) if args.json else (lambda s: print(s, flush=True))
    arm = Ros2Arm(Ros2ArmConfig(v=args.v, a=args.a, convention=args.convention), domain, args.network, log=say)
    outcome: dict[str, object] = {"start": start + 1, "end": end + 1, "blocks": n_blocks, "domain_id": domain,
                                  "network": args.network, "convention": args.convention}
    try:
        arm.connect()
        say(f"connected on ROS_DOMAIN_ID {domain} ({args.network}): {n_blocks} blocks, tower {start + 1} -> {end + 1}")
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
