"""The ROS 2 subcommands of ``ur3hanoi``: ``ros2-station`` and ``ros2-solve`` (the course topics: no ROS installation,
Cyclone DDS) and ``ros2-env`` (rclpy for the UR driver's interface).

Conventions as in :mod:`ur3hanoi.cli.ros`: towers, heights, blocks and grasps numbered from 1; errors one line with
exit code 2; a suction fault exits with 3. Heavy imports (MuJoCo, Cyclone DDS) happen only when a command runs.
"""

from __future__ import annotations

import argparse
import sys

from ur3hanoi.cli import driver, remote

DEFAULT_ROS2_CALIBRATION = "ur3e_sim"
_DOMAIN_HELP = "ROS_DOMAIN_ID, 0..232 (default: $ROS_DOMAIN_ID, else 0)"
_NETWORK_HELP = ("DDS network: loopback (default: nothing leaves this machine), lab (join the lab network: "
                 "Cyclone's interface choice, multicast discovery) or a network interface name")


_STATION_HELP = ("run the MuJoCo station as the ROS 2 course bridge (ur3e/command, position, gripper_input) "
                 "without ROS")
_STATION_DESCRIPTION = (
    "The ROS 2 course bridge (UMD ENME480 ur3e_mrc_msgs) over Cyclone DDS, no ROS installation: "
    "subscribes ur3e/command (CommandUR3e), publishes ur3e/position (PositionUR3e), "
    "ur3e/gripper_input (GripperInput: the suction model's dig_in/a_in0) and gripper/grasping "
    "(Bool), default QoS, node ur3hanoi_station. Topics ur3hanoi/spawn (std_msgs/Int32 tower) and "
    "ur3hanoi/remove_block (block, 1 = bottom) respawn and remove blocks. Bridge behaviour by default: destinations of "
    "length != 6 dropped with a log line, every move 2 s (v and a ignored), is_ready always true, "
    "joint values in the bridge's convention (controller = course + [pi/2, 0, 0, -pi/2, 0, 0]). "
    "Loopback only unless --network. On SIGINT/SIGTERM (SIGUSR1: without stopping) writes a JSON "
    "report to --report or stdout.")

_SOLVE_HELP = "solve the puzzle through ur3e/command (ros2-station or the course's UR3e bridge)"
_SOLVE_DESCRIPTION = (
    "ros-solve over the ROS 2 course interface: moves every block with a waypoint table "
    "(--table FILE --key, controller convention, or generated from --calibration), waits until "
    "every joint is within 0.0008 rad, checks dig_in bit 0 after every grasp and during every "
    "carry, and on a missing or dropped block halts: suction off, arm home, error, exit 3.")


def _domain(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"invalid value {text!r}: expected an integer in [0, 232]") from None
    if not 0 <= value <= 232:
        raise argparse.ArgumentTypeError(f"invalid value {value}: expected an integer in [0, 232]")
    return value


def add_dds_options(p: argparse.ArgumentParser) -> None:
    """``--convention``, ``--network``, ``--domain-id``."""
    p.add_argument("--convention", choices=["course", "controller"], default="course",
                   help="joint convention on the topics (default course, the bridge's)")
    p.add_argument("--network", default="loopback", metavar="NET", help=_NETWORK_HELP)
    p.add_argument("--domain-id", type=_domain, default=None, metavar="ID", help=_DOMAIN_HELP)


def add(sub: argparse._SubParsersAction) -> None:
    """Add ``ros2-station``, ``ros2-solve`` and ``ros2-env`` to ``sub``."""
    _add_station(sub)
    _add_solve(sub)
    _add_env(sub)


def _add_station(sub: argparse._SubParsersAction) -> None:
    p = remote.station_parser(
        sub, "ros2-station", _STATION_HELP, _STATION_DESCRIPTION, DEFAULT_ROS2_CALIBRATION, "a_in0")
    p.add_argument("--timing", choices=["bridge", "honest"], default="bridge",
                   help="bridge: fixed 2 s moves, is_ready always true (default); honest: the controller's movej at "
                        "the message's v and a, is_ready = arrived")
    add_dds_options(p)
    driver.add_driver_option(p, station=True)
    add_distro_option(p)
    remote.add_station_outputs(p)
    p.set_defaults(func=_run_station)


def add_distro_option(p: argparse.ArgumentParser) -> None:
    """``--ros-distro``: the UR driver's names and controller rules (with ``--driver ur``)."""
    from ur3hanoi.interface.ros2.distros import ROS_DISTROS

    p.add_argument("--ros-distro", choices=list(ROS_DISTROS), default=None, metavar="DISTRO",
                   help="with --driver ur: the robot's ROS 2 distribution, humble, jazzy, kilted (the scaled "
                        "trajectory controller) or lyrical (joint_trajectory_controller); default $ROS_DISTRO if it "
                        "is one of these, else jazzy")


def _distro(args: argparse.Namespace) -> str:
    from ur3hanoi.interface.ros2.distros import default_distro

    return str(args.ros_distro or default_distro())


def _run_station(args: argparse.Namespace) -> int:
    driver.program_times(args)  # a contradiction in the program options: one line before any work
    report_file = remote.check_station_outputs(args, DEFAULT_ROS2_CALIBRATION)  # before any work
    fields = remote.station_options(args, DEFAULT_ROS2_CALIBRATION, report_file)
    if args.driver == "ur":
        from ur3hanoi.interface.ros2.rclpy_env import import_rclpy
        from ur3hanoi.interface.ros2.ur_station import Ros2DriverOptions, Ros2DriverStation

        import_rclpy()  # say what is missing before loading the world

        stop, resume = driver.program_times(args)
        with remote.ReportStdout() as report_out:
            report = Ros2DriverStation(Ros2DriverOptions(**fields, speed_scaling=args.speed_scaling,
                                                         distro=_distro(args), network=args.network,
                                                         domain_id=args.domain_id, program_stop_at_s=stop,
                                                         program_resume_at_s=resume), report_out=report_out).run()
    else:
        from ur3hanoi.interface.ros2.server import Ros2Server, Ros2ServerOptions

        options = Ros2ServerOptions(**fields, timing=args.timing, convention=args.convention, network=args.network,
                                    domain_id=args.domain_id)
        with remote.ReportStdout() as report_out:
            report = Ros2Server(options, report_out=report_out).run()
    if report_file is not None:
        print(remote.stopped_line("ros2-station", report, f"report {args.report}"), file=sys.stderr, flush=True)
    return 0


def _add_solve(sub: argparse._SubParsersAction) -> None:
    p = remote.solve_parser(
        sub, "ros2-solve", _SOLVE_HELP, _SOLVE_DESCRIPTION,
        f"station calibration: the table's source and the home pose (default {DEFAULT_ROS2_CALIBRATION})",
        ("; the course bridge ignores it", "; ignored by the bridge"), 1.0)
    add_dds_options(p)
    driver.add_driver_option(p, station=False)
    add_distro_option(p)
    remote.add_json_option(p)
    p.set_defaults(func=_run_solve)


def _run_solve(args: argparse.Namespace) -> int:
    from ur3hanoi.errors import InputError
    from ur3hanoi.interface.ros2.client import Ros2Arm, Ros2ArmConfig
    from ur3hanoi.interface.ros2.dds import domain_id_from_env

    job = remote.solve_job(args, "ros2-solve", DEFAULT_ROS2_CALIBRATION, station_optional=args.driver == "course")
    if args.driver == "ur":
        from ur3hanoi.interface.ros2.rclpy_env import import_rclpy
        from ur3hanoi.interface.ros2.ur_client import RclpyDriverTransport

        import_rclpy()  # say what is missing before anything else
        transport = RclpyDriverTransport(_distro(args), args.domain_id, args.network, args.wait)
        outcome_ur: dict[str, object] = {"start": job.start + 1, "end": job.end + 1, "blocks": job.n_blocks,
                                         "ros_distro": transport.distro, "network": args.network}
        return driver.run_driver_solve_command(
            args, transport, lambda: driver.driver_plan(args, job, DEFAULT_ROS2_CALIBRATION), outcome_ur)
    try:
        domain = domain_id_from_env() if args.domain_id is None else args.domain_id
    except ValueError as exc:
        raise InputError(str(exc)) from None
    arm = Ros2Arm(Ros2ArmConfig(v=args.v, a=args.a, convention=args.convention), domain, args.network,
                  log=remote.say_for(args))
    outcome: dict[str, object] = {"start": job.start + 1, "end": job.end + 1, "blocks": job.n_blocks,
                                  "domain_id": domain, "network": args.network, "convention": args.convention}
    connected = (f"connected on ROS_DOMAIN_ID {domain} ({args.network}): {job.n_blocks} blocks, tower "
                 f"{job.start + 1} -> {job.end + 1}")
    return remote.drive(args, arm, job, connected, outcome)


_ENV_DESCRIPTION = (
    "Build once, in the user cache, a separate environment with the ROS 2 rclpy wheels from PyPI for this Python "
    "(Jazzy: Fast-RTPS 2.14; Kilted: Fast DDS 3.2) and the UR driver's control_msgs and ur_msgs built from their "
    "official texts (needs cmake, make, a C++ compiler and this Python's headers; about 2 minutes the first time), "
    "then print the lines that let ur3hanoi use it: eval \"$(ur3hanoi ros2-env)\". Humble and Jazzy robots share "
    "one environment, Kilted and Lyrical (control_msgs >= 6.3) the other. Not needed with a sourced ROS 2 "
    "installation built for this Python.")


def _add_env(sub: argparse._SubParsersAction) -> None:
    from ur3hanoi.interface.ros2.distros import ROS_DISTROS

    p = sub.add_parser("ros2-env", help="build rclpy and the UR driver's messages once, print the environment to eval",
                       description=_ENV_DESCRIPTION)
    p.add_argument("--distro", choices=sorted(ROS_DISTROS), default=None,
                   help="the robot's ROS 2 distribution (default: $ROS_DISTRO if it is one of these, else jazzy)")
    p.add_argument("--dir", metavar="DIR", help="folder of the environments (default: $XDG_CACHE_HOME/ur3hanoi)")
    p.set_defaults(func=_run_env)


def _run_env(args: argparse.Namespace) -> int:
    import sys
    from pathlib import Path

    from ur3hanoi.interface.ros2.distros import ROS_DISTROS, default_distro
    from ur3hanoi.interface.ros2.rclpy_build import WHEELS, ensure_env
    from ur3hanoi.io.cache import cache_dir

    distro = args.distro or default_distro()
    cache = Path(args.dir).resolve() if args.dir else cache_dir()

    def log(line: str) -> None:
        print(f"# ur3hanoi ros2-env: {line}", file=sys.stderr, flush=True)

    env = ensure_env(cache, WHEELS[ROS_DISTROS[distro]], sys.executable, log=log)
    log(f"rclpy ({env.wheels} wheels, Python {env.python}) and {', '.join(env.packages)} in {env.root}")
    for line in env.shell_lines(distro):
        print(line)
    return 0
