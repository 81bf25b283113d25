"""The ROS subcommands of ``ur3hanoi``: ``ros-station``, ``ros-solve`` and ``ros-env``.

:func:`add` adds them to the main parser's subparsers. Conventions as in the other subcommands (numeric ranges
in :mod:`ur3hanoi.cli.options`): towers, heights, blocks and grasps numbered from 1; ``--calibration`` takes a shipped
station name (``lab_sim``) or a file; errors are one line ``ur3hanoi: error: ...`` with exit code 2, a suction
fault exits with 3. Heavy imports (MuJoCo, rospy) happen only when a command runs.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import TYPE_CHECKING

from ur3hanoi.cli import driver, remote
from ur3hanoi.cli.common import DEFAULT_CALIBRATION

if TYPE_CHECKING:
    from ur3hanoi.interface.ros1.server import RosStation

_STATION_HELP = "run the MuJoCo station as the course's ROS driver (ur3/command, position, gripper_input)"
_STATION_DESCRIPTION = (
    "A drop-in for the course's Gazebo world and ur3_driver: executes ur3/command as the UR "
    "controller's movej (v and a capped at the UR3 limits: 180 deg/s joints 1-3, 360 deg/s wrists, "
    "4/8 rad/s^2), switches suction with io_0, publishes ur3/position and ur3/gripper_input at "
    "--rate in real time. Topics ur3hanoi/spawn (std_msgs/Int32 tower) and ur3hanoi/remove_block "
    "(block, 1 = bottom) respawn and remove blocks. Starts a roscore when none answers (stopped "
    "with the station, even when it is killed). Listens on 127.0.0.1 only unless --host. Refuses "
    "moves longer than 60 s and more than 100 waiting commands; logs at most one line per topic "
    "and second. On SIGINT/SIGTERM (and SIGUSR1, without stopping) writes a JSON report to "
    "--report or stdout; everything else goes to stderr.")

_SOLVE_HELP = "solve the puzzle through ur3/command like the lab program (ros-station or the real UR3)"
_SOLVE_DESCRIPTION = (
    "The lab program, done right: moves every block through the course's ROS interface with a "
    "waypoint table (--table FILE --key sim_pos|real_pos, or generated from --calibration), checks "
    "the suction feedback (DIGIN bit 0) after every grasp and during every carry, and on a missing "
    "or dropped block halts like the lab asks: suction off, arm home, error, exit 3. Without "
    "--start/--end it prompts like the lab program. Towers are numbered from 1.")


def _master_help() -> str:
    return "ROS master URI (default: $ROS_MASTER_URI, else http://localhost:11311)"


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``ros-station``, ``ros-solve`` and ``ros-env`` to ``sub``."""
    _add_station(sub)
    _add_solve(sub)
    _add_env(sub)


# ------------------------------------------------------------------------------------------------ ros-station


def _add_station(sub: argparse._SubParsersAction) -> None:
    p = remote.station_parser(
        sub, "ros-station", _STATION_HELP, _STATION_DESCRIPTION, DEFAULT_CALIBRATION, "AIN0", ", CB3")
    p.add_argument("--master", metavar="URI", help=_master_help())
    p.add_argument("--host", metavar="ADDR", default="127.0.0.1",
                   help="address the station and the roscore it starts listen on and advertise (ROS_IP); default "
                        "127.0.0.1: this machine only. Give this machine's lab-network address to open them to "
                        "other machines (a master on another machine needs it)")
    driver.add_driver_option(p, station=True)
    remote.add_station_outputs(p)
    p.set_defaults(func=_run_station)


def _node(args: argparse.Namespace, report_file: Path | None) -> RosStation:
    """The station node: the course's topics, or the UR driver's interface (``--driver ur``)."""
    from ur3hanoi.interface.ros1.server import RosServer, RosServerOptions

    fields = remote.station_options(args, DEFAULT_CALIBRATION, report_file)
    if args.driver == "ur":
        from ur3hanoi.interface.ros1.ur_server import RosDriverOptions, RosDriverServer

        stop, resume = driver.program_times(args)
        return RosDriverServer(RosDriverOptions(**fields, master_uri=args.master, host=args.host,
                                                speed_scaling=args.speed_scaling, program_stop_at_s=stop,
                                                program_resume_at_s=resume))
    return RosServer(RosServerOptions(**fields, master_uri=args.master, host=args.host))


def _run_station(args: argparse.Namespace) -> int:
    driver.program_times(args)  # a contradiction in the program options: one line before any work
    report_file = remote.check_station_outputs(args, DEFAULT_CALIBRATION)  # before any work
    node = _node(args, report_file)
    with remote.ReportStdout() as report_out:
        node.report_out = report_out
        report = node.run()
    if report_file is not None and args.driver == "ur":
        print(remote.stopped_line("ros-station", report, f"report {args.report}"), file=sys.stderr, flush=True)
    elif report_file is not None:
        blocks = ", ".join(f"{b['block']} " + ("off-grid" if b["tower"] is None else
                                              f"tower {b['tower']} height {b['height']}")
                           for b in report["final"]["blocks"])
        lag = 1e3 * report["control"]["worst_lag_s"]
        print(remote.stopped_line("ros-station", report, f"blocks {blocks}; worst loop lag {lag:.2f} ms; report "
                                                  f"{args.report}"), file=sys.stderr, flush=True)
    return 0


# -------------------------------------------------------------------------------------------------- ros-solve


def _add_solve(sub: argparse._SubParsersAction) -> None:
    p = remote.solve_parser(
        sub, "ros-solve", _SOLVE_HELP, _SOLVE_DESCRIPTION,
        f"station calibration: the table's source without --table, and the home pose (default "
        f"{DEFAULT_CALIBRATION}; with --table and no --calibration: the lab's home)",
        (", the lab's; capped by the driver", ", the lab's"), 4.0)
    p.add_argument("--master", metavar="URI", help=_master_help())
    driver.add_driver_option(p, station=False)
    remote.add_json_option(p)
    p.set_defaults(func=_run_solve)


def _run_solve(args: argparse.Namespace) -> int:
    from ur3hanoi.interface.ros1.client import ArmConfig, RosArm

    job = remote.solve_job(args, "ros-solve", DEFAULT_CALIBRATION, station_optional=args.driver == "course")
    if args.driver == "ur":
        from ur3hanoi.interface.ros1.ur_client import RosDriverTransport

        outcome_ur: dict[str, object] = {"start": job.start + 1, "end": job.end + 1, "blocks": job.n_blocks}
        return driver.run_driver_solve_command(args, RosDriverTransport(args.master, args.wait),
                                               lambda: driver.driver_plan(args, job, DEFAULT_CALIBRATION), outcome_ur)
    arm = RosArm(ArmConfig(v=args.v, a=args.a), master_uri=args.master, log=remote.say_for(args))
    outcome: dict[str, object] = {"start": job.start + 1, "end": job.end + 1, "blocks": job.n_blocks, "v": args.v,
                                  "a": args.a}
    connected = f"connected to {arm.master_uri}: {job.n_blocks} blocks, tower {job.start + 1} -> {job.end + 1}"
    return remote.drive(args, arm, job, connected, outcome)


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
    p.add_argument("--driver", choices=driver.DRIVERS, default="course",
                   help="ur: also write the official UR driver's message packages (control_msgs, "
                        "controller_manager_msgs, cartesian_control_msgs, std_srvs, ur_dashboard_msgs), so UR's own "
                        "clients (ur_robot_driver's scripts/test_move) run against ros-station --driver ur")
    p.set_defaults(func=_run_env)


def _run_env(args: argparse.Namespace) -> int:
    from ur3hanoi.interface.ros1.env import default_cache_dir, env_lines
    from ur3hanoi.interface.ros1.master import MasterUri, master_uri_from_env
    from ur3hanoi.interface.ros1.msgs import write_client_env

    folder = Path(args.dir).resolve() if args.dir else default_cache_dir()
    uri = args.master or master_uri_from_env()
    MasterUri.parse(uri)
    files = write_client_env(folder)
    what = "ur3_driver messages"
    if args.driver == "ur":
        from ur3hanoi.interface.ros1.ur_packages import write_ur_packages

        files += write_ur_packages(folder)
        what += " and the UR driver's message packages"
    print(f"# ur3hanoi ros-env: wrote {len(files)} files ({what}) to {folder}", file=sys.stderr)
    for line in env_lines(folder, uri):
        print(line)
    return 0
