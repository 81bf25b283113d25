"""``ur3hanoi plan``: solve a Hanoi instance and time-parameterize the motion with Ruckig."""

from __future__ import annotations

import argparse

from ur3hanoi.cli.common import (
    DEFAULT_CALIBRATION,
    SYMLINK_NOTE,
    calibration_ref,
    input_file,
    require_replay,
    shown,
)
from ur3hanoi.cli.options import (
    BLOCKS,
    DWELL,
    RATE,
    SPEED,
    check_blocks,
    check_number,
    check_plan_size,
    option,
    station_number,
)


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan", help="solve a Hanoi instance and time-parameterize the motion with Ruckig",
                       description="Solve the Tower of Hanoi from --start to --end (towers and blocks numbered "
                                   "from 1) and plan the whole motion with Ruckig under the UR3's limits "
                                   "(pass-through above the towers, vertical approach within 2 mm), checked for "
                                   "joint limits, velocity/acceleration/jerk and clearances.")
    p.add_argument("--start", type=station_number("a tower number"), required=True,
                   help="start tower (1-based, 1..the station's towers)")
    p.add_argument("--end", type=station_number("a tower number"), required=True,
                   help="end tower (1-based, 1..the station's towers)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None,
                   help=f"{BLOCKS.expected()} (default: the grid's heights)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML (default {DEFAULT_CALIBRATION})")
    p.add_argument("--speed", type=option(SPEED), default=1.0,
                   help=f"scale of the velocity, acceleration and jerk limits, in [{SPEED.lo:g}, {SPEED.hi:g}] "
                        "(default 1)")
    p.add_argument("--rate", type=option(RATE), default=125.0,
                   help=f"sample rate [Hz] in [{RATE.lo:g}, {RATE.hi:g}]: 125 (CB3, default) or 500 (e-Series)")
    p.add_argument("--dwell", type=option(DWELL), default=0.3,
                   help=f"suction dwell at each contact [s] in [{DWELL.lo:g}, {DWELL.hi:g}] (default 0.3)")
    p.add_argument("--csv", metavar="FILE",
                   help=f"write t,q1..q6,qd1..qd6,suction,move,phase samples to FILE ({SYMLINK_NOTE})")
    p.add_argument("--html", metavar="FILE",
                   help="write a replay page of the plan: one offline HTML file (3-D arm and blocks, timeline, move "
                        "and suction state); FILE#t=12.5 opens at 12.5 s")
    p.add_argument("--plot", metavar="FILE",
                   help="draw joint positions and speeds against time with the limits, phases shaded, into FILE "
                        "(.png, .svg or .pdf; needs the plot extra)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.add_argument("--no-collision", action="store_true", help="skip the (slower) clearance checks")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import json

    from ur3hanoi.plan import PlanConfig, plan_json_dict, plan_solve, trajectory_csv
    from ur3hanoi.station.calibration import load_station

    inputs = [input_file(calibration_ref(args.calibration))]
    if args.csv or args.html:
        from ur3hanoi.io.atomic import atomic_write, check_output  # the writer, only when the plan writes a file
    if args.csv:
        check_output(args.csv, inputs=inputs)  # fail before planning, not after
    if args.html:
        require_replay()
        check_output(args.html, inputs=inputs)
    if args.plot:
        from ur3hanoi.plots import check_plot_path, require_matplotlib

        require_matplotlib()
        check_plot_path(args.plot, tuple(inputs))
    station = load_station(calibration_ref(args.calibration))
    for name, value in (("--start", args.start), ("--end", args.end)):
        check_number(name, value, station.n_towers, "a tower", f"{station.name} has {station.n_towers} towers")
    n_blocks = station.n_heights if args.blocks is None else args.blocks
    check_blocks(n_blocks, station.n_heights, given=args.blocks is not None)
    check_plan_size(n_blocks, args.speed, args.dwell, args.rate)
    config = PlanConfig(speed=args.speed, rate_hz=args.rate, dwell_s=args.dwell,
                        check_collisions=not args.no_collision)
    plan = plan_solve(station, args.start - 1, args.end - 1, n_blocks, config)
    if args.csv:
        atomic_write(args.csv, trajectory_csv(plan.trajectory), inputs=inputs)
    if args.plot:
        from ur3hanoi.plots.plan import write_plan_plot

        write_plan_plot(args.plot, plan, f"{station.name}: {n_blocks} blocks, tower {args.start} -> {args.end}, "
                                         f"speed {args.speed:g}", tuple(inputs))
    html_size = None
    if args.html:
        from ur3hanoi.replay import write_plan_replay
        from ur3hanoi.sim import build_task_scene

        scene = build_task_scene(station, args.start - 1, n_blocks)
        title = f"{station.name}: plan of {n_blocks} blocks, tower {args.start} -> {args.end}"
        html_size = write_plan_replay(args.html, plan, scene, title, tuple(inputs))
    if args.json:
        print(json.dumps(plan_json_dict(plan)))
        return 0
    print(f"{shown(station.name)}: {n_blocks} blocks, tower {args.start} -> {args.end}: {len(plan.moves)} moves")
    for i, m in enumerate(plan.moves, start=1):
        d = m.as_lab_dict()
        print(f"  {i:>3}. block {d['block']}: tower {d['from_tower']} height {d['from_height']} -> "
              f"tower {d['to_tower']} height {d['to_height']}")
    print(f"cycle {plan.duration_s:.3f} s (motion {plan.motion_s:.3f} s); joint-space stop-and-go baseline "
          f"{plan.stop_and_go_duration_s:.3f} s (motion {plan.stop_and_go_motion_s:.3f} s): "
          f"{100 * plan.motion_saving:.1f} % less motion time")
    print(f"{len(plan.trajectory.t)} samples at {plan.trajectory.rate_hz:g} Hz, speed {args.speed:g}; all limit and "
          "clearance checks passed" + (f"; wrote {shown(args.csv)}" if args.csv else ""))
    if html_size is not None:
        print(f"wrote the replay page {shown(args.html)} ({html_size / 1e6:.1f} MB)")
    if args.plot:
        print(f"wrote {shown(args.plot)}")
    return 0
