"""The ``--driver ur`` options of the station and solve subcommands of both middlewares (:mod:`ur3hanoi.cli.ros`,
:mod:`ur3hanoi.cli.ros2`): the official UR driver's interface instead of the course's topics.

A station serves it from MuJoCo (``--speed-scaling``: the pendant's slider); a solve executes the Ruckig plan on it
(:func:`ur3hanoi.interface.urdriver.solve.run_driver_solve`), the plan made from ``--calibration`` (the plan of
``ur3hanoi plan``) or from a hand-recorded ``--table`` (its waypoints moved rest to rest like the lab program,
:func:`ur3hanoi.plan.plan_table`; the station is still needed for the limits and home: ``--calibration`` or the
default's).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from ur3hanoi.cli.options import DRIVER_WAIT, SIM_TIME, SPEED_SLIDER, option

if TYPE_CHECKING:
    from ur3hanoi.cli.remote import SolveJob
    from ur3hanoi.plan import Plan

DRIVERS = ("course", "ur")
"""``--driver``: the course's topics (``ur3/command`` ...) or the official UR driver's interface."""


def add_driver_option(p: argparse.ArgumentParser, station: bool) -> None:
    """``--driver`` (and on a station ``--speed-scaling``; on a solve ``--far-start``)."""
    what = ("serve the official UR driver's interface (joint_states, the scaled trajectory controller's "
            "follow_joint_trajectory action, set_io, io_states, speed scaling) instead of the course's topics"
            if station else "drive the official UR driver's scaled trajectory controller with the whole Ruckig plan "
            "(goals with positions, velocities and accelerations; suction by set_io on the calibration's pins)")
    p.add_argument("--driver", choices=DRIVERS, default="course", help=f"course (default) or ur: {what}")
    if station:
        p.add_argument("--speed-scaling", type=option(SPEED_SLIDER), default=1.0, metavar="F",
                       help="with --driver ur: the pendant's speed slider, a fraction in (0, 1] (default 1): the "
                            "trajectory controller's time runs this much slower")
        p.add_argument("--program-stop-at", type=option(SIM_TIME), default=None, metavar="S",
                       help="with --driver ur, fault injection: the External Control program stops S seconds after "
                            "the station starts (0: stopped from the start), as the pendant's stop button does: "
                            "robot_program_running turns false, the running goal ends, new goals are refused")
        p.add_argument("--program-resume-at", type=option(SIM_TIME), default=None, metavar="S",
                       help="with --driver ur and --program-stop-at: the program runs again S seconds after the "
                            "station starts (the pendant's play button)")
    else:
        p.add_argument("--far-start", choices=("approach", "refuse"), default="approach",
                       help="with --driver ur, an arm far from where the plan starts: approach = move it there "
                            "first at 25 %% speed (default), refuse = stop with the distance")
        p.add_argument("--wait", type=option(DRIVER_WAIT), default=15.0, metavar="S",
                       help="with --driver ur: wait at most S seconds for the driver's joint states, io_states, "
                            "action server and set_io (default 15)")


def program_times(args: argparse.Namespace) -> tuple[float | None, float | None]:
    """``--program-stop-at`` and ``--program-resume-at`` [s] (one line when they contradict)."""
    from ur3hanoi.errors import InputError

    stop, resume = args.program_stop_at, args.program_resume_at
    if resume is not None and (stop is None or resume <= stop):
        raise InputError(f"--program-resume-at {resume:g} needs an earlier --program-stop-at (got "
                         f"{'none' if stop is None else f'{stop:g}'}): the program can only start again after it "
                         "stopped")
    if stop is not None and args.driver != "ur":
        raise InputError("--program-stop-at needs --driver ur (the course's topics have no robot program)")
    return stop, resume


def driver_plan(args: argparse.Namespace, job: SolveJob, default_calibration: str) -> Plan:
    """The plan the driver executes: Ruckig through the station's IK table, or through ``--table``'s waypoints."""
    from ur3hanoi.plan import PlanConfig, plan_solve, plan_table
    from ur3hanoi.station.calibration import load_station

    station = load_station(args.calibration or default_calibration)
    if args.table is not None:
        return plan_table(station, job.Q, job.start, job.end, job.n_blocks, PlanConfig(),
                          where=f"{args.table}:{args.key or 'sim_pos'}")
    return plan_solve(station, job.start, job.end, job.n_blocks, PlanConfig())


def run_driver_solve_command(args: argparse.Namespace, transport: Any, make_plan: Callable[[], Plan],
                             outcome: dict[str, object]) -> int:
    """Connect ``transport`` (no driver: an error at once, before planning), plan, run the plan, print the outcome
    (one JSON object with ``--json``); a suction fault or a stopped robot program is re-raised (exit 3) after its
    outcome is printed; every other error propagates (exit 2)."""
    import json

    from ur3hanoi.cli.remote import say_for
    from ur3hanoi.errors import ProgramStoppedError, SuctionFaultError
    from ur3hanoi.interface.urdriver.solve import DriverSolveConfig, run_driver_solve

    say = say_for(args)
    config = DriverSolveConfig(grasp_timeout_s=args.grasp_timeout, far_start=args.far_start)
    try:
        transport.connect()
        plan = make_plan()
        outcome.update(driver="ur", plan_duration_s=round(plan.duration_s, 3))
        say(f"connected to the UR driver on {transport.where}: {len(plan.moves)} moves, plan {plan.duration_s:.1f} s")
        try:
            result = run_driver_solve(transport, plan, plan.station.wiring, config, log=say)
        except (SuctionFaultError, ProgramStoppedError) as exc:
            outcome.update(status="halted", exit_code=exc.exit_code, error=str(exc))
            if args.json:
                print(json.dumps(outcome))
            raise
    finally:
        transport.close()
    outcome.update(status="solved", exit_code=0, moves=len(result.moves), goals=result.goals,
                   wall_time_s=round(result.wall_time_s, 3), executed_s=round(result.executed_s, 3),
                   approach_s=round(result.approach_s, 3), **({} if result.path is None else result.path.as_dict()))
    if args.json:
        print(json.dumps(outcome))
    else:
        print(f"solved: {len(result.moves)} moves in {result.goals} goals, {result.executed_s:.1f} s (the plan: "
              f"{plan.duration_s:.1f} s)" + (f" after {result.approach_s:.1f} s to its start" if result.approach_s
                                             else "") + ("" if result.path is None else f"; {result.path.describe()}"))
    sys.stdout.flush()
    return 0
