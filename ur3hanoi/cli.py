"""The ``ur3hanoi`` command line. Every user error prints one line ``ur3hanoi: error: ...`` and exits non-zero
(2 for bad input or unreachable poses, 3 for a suction fault); no output file is left half-written.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi import __version__
from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.ros.cli import add_ros_commands

DEFAULT_CALIBRATION = "lab_sim"


def _positive_float(text: str) -> float:
    try:
        x = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not math.isfinite(x) or x <= 0:
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive number")
    return x


# ----------------------------------------------------------------------------------------------------- tables


def _add_tables(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("tables", help="generate a lab2_data.yaml waypoint table from a calibration by IK",
                       description="Generate Q[tower][height][0 = on, 1 = above] (6 joint angles [rad]) by IK "
                                   "and write it under --key into FILE, keeping every other key of FILE.")
    p.add_argument("calibration", help="station calibration YAML, or a shipped station name (lab_sim, lab_real)")
    p.add_argument("--key", required=True, choices=["sim_pos", "real_pos"], help="table key to (re)generate")
    p.add_argument("-o", "--output", required=True, metavar="FILE", help="lab-format YAML file to create/update")
    p.add_argument("--solver", default="pinocchio", choices=["pinocchio", "placo"], help="IK solver")
    p.set_defaults(func=_run_tables)


def _run_tables(args: argparse.Namespace) -> int:
    from ur3hanoi.station import load_station
    from ur3hanoi.table import generate_table, write_table

    station = load_station(args.calibration)
    table = generate_table(station, args.solver)
    write_table(args.output, table, args.key, calibration_label=Path(args.calibration).as_posix())
    print(
        f"wrote {args.key} ({station.n_towers} towers x {station.n_heights} heights x 2) to {args.output}: "
        f"max IK error {table.max_position_error:.2e} m, {table.max_orientation_error:.2e} rad ({args.solver})"
    )
    return 0


# ------------------------------------------------------------------------------------------------ check-table


def _add_check_table(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-table", help="FK-check every entry of a lab-format table against a calibration",
                       description="Report, for every Q[tower][height][k] of FILE, the FK position [mm] and "
                                   "orientation [deg] error of the suction point against the calibration's "
                                   "intended pose; exit 1 if any entry exceeds the tolerance.")
    p.add_argument("file", help="lab-format YAML (generated or hand-recorded)")
    p.add_argument("--key", required=True, help="table key, e.g. sim_pos or real_pos")
    p.add_argument("--calibration", required=True, help="station calibration YAML")
    p.add_argument("--tol-mm", type=_positive_float, default=1.0, help="position tolerance [mm] (default 1)")
    p.add_argument("--tol-deg", type=_positive_float, default=0.5, help="orientation tolerance [deg] (default 0.5)")
    p.set_defaults(func=_run_check_table)


def _run_check_table(args: argparse.Namespace) -> int:
    from ur3hanoi.station import load_station
    from ur3hanoi.table import check_table, read_table

    station = load_station(args.calibration)
    q = read_table(args.file, args.key)
    rows = check_table(q, station, args.tol_mm, args.tol_deg, where=f"{args.file}:{args.key}")
    print(f"{'tower':>5} {'height':>6} {'pose':>5} {'pos [mm]':>10} {'rot [deg]':>10}  status")
    for r in rows:
        status = "ok" if r.ok else "FAIL"
        print(f"{r.tower:>5} {r.height:>6} {('on', 'above')[r.k]:>5} {r.position_error_mm:>10.4f} "
              f"{r.orientation_error_deg:>10.4f}  {status}")
    bad = [r for r in rows if not r.ok]
    worst_mm = max(r.position_error_mm for r in rows)
    worst_deg = max(r.orientation_error_deg for r in rows)
    print(f"{len(rows) - len(bad)}/{len(rows)} entries within {args.tol_mm} mm / {args.tol_deg} deg "
          f"(worst {worst_mm:.4f} mm, {worst_deg:.4f} deg)")
    return 1 if bad else 0


# -------------------------------------------------------------------------------------------------- calibrate


def _add_calibrate(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="fit a station's tower grid to taught poses (least squares)",
                       description="Fit the tower origins, height step, approach and tool yaw of a station to "
                                   "taught joint poses (or to every entry of an existing lab-format table); "
                                   "everything else comes from --base. Prints the residual of every point [mm] "
                                   "and warns about points over 2 mm. See `ur3hanoi.calibrate` for the format.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--taught", metavar="FILE", help="taught-points YAML (units: deg|rad; points: [...])")
    src.add_argument("--from-table", metavar="FILE", help="lab-format table whose entries are the taught points")
    p.add_argument("--key", help="table key with --from-table (sim_pos or real_pos)")
    p.add_argument("--base", required=True, metavar="CALIBRATION",
                   help="station calibration providing robot base, tool, blocks, home, counts and layout")
    p.add_argument("-o", "--output", required=True, metavar="OUT", help="calibration YAML to write")
    p.add_argument("--name", help="station name written to OUT (default: OUT's file name without extension)")
    p.set_defaults(func=_run_calibrate)


def _run_calibrate(args: argparse.Namespace) -> int:
    from ur3hanoi.calibrate import fit_station, load_taught, taught_from_table, write_calibration
    from ur3hanoi.errors import TaughtPointsError
    from ur3hanoi.station import load_station

    if args.from_table is not None and args.key is None:
        raise TaughtPointsError("--from-table needs --key (sim_pos or real_pos)")
    if args.taught is not None and args.key is not None:
        raise TaughtPointsError("--key is only used with --from-table")
    inputs = [args.base, args.taught or args.from_table]
    out = Path(args.output)
    if any(out.exists() and Path(f).exists() and out.resolve() == Path(f).resolve() for f in inputs):
        raise TaughtPointsError(f"output {args.output} is one of the input files: choose another -o")
    base = load_station(args.base)
    if args.taught is not None:
        taught = load_taught(args.taught)
        taught_label = Path(args.taught).as_posix()
    else:
        taught = taught_from_table(args.from_table, args.key)
        taught_label = f"{Path(args.from_table).as_posix()} key {args.key}"
    fit = fit_station(base, taught, name=args.name or out.stem, source=str(args.output))
    write_calibration(out, fit, taught, base, taught_label=taught_label, base_label=Path(args.base).as_posix())

    print(f"{'point':>6} {'tower':>5} {'height':>6} {'pose':>5} {'res [mm]':>9} {'dx':>7} {'dy':>7} {'dz':>7} "
          f"{'yaw [deg]':>9} {'tilt':>6}")
    for r in fit.residual_table():
        print(f"{r.index:>6} {r.tower:>5} {r.height:>6} {r.pose:>5} {r.residual_mm:>9.3f} {r.dx_mm:>7.3f} "
              f"{r.dy_mm:>7.3f} {r.dz_mm:>7.3f} {r.yaw_dev_deg:>9.3f} {r.tilt_deg:>6.2f}{'  <-' if r.flagged else ''}")
    for w in fit.warnings:
        print(f"ur3hanoi: warning: {w}", file=sys.stderr)
    exact = " (exact fit: add points to check it)" if fit.dof == 0 else ""
    print(f"wrote {args.output}: fitted {', '.join(fit.fitted_params)} from {len(fit.points)} points, "
          f"residual rms {fit.rms_mm:.3f} mm, max {fit.max_mm:.3f} mm{exact}; {len(fit.warnings)} warning(s)")
    return 0


# ------------------------------------------------------------------------------------------------------ solve


def _add_solve(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("solve", help="run the lab in MuJoCo: plan, execute with suction feedback, verify",
                       description="Solve the Tower of Hanoi in a MuJoCo simulation of the station: the UR3 "
                                   "follows the planned trajectory, the suction cup grasps by weld, and the "
                                   "program halts like the lab's (suction off, arm home, exit 3) when a block is "
                                   "missing or dropped. Towers, heights and moves are numbered from 1. Without "
                                   "--start/--end it prompts on a terminal like the lab program.")
    p.add_argument("--start", type=int, metavar="S", help="start tower (1-based)")
    p.add_argument("--end", type=int, metavar="E", help="destination tower (1-based)")
    p.add_argument("--blocks", type=int, default=None, metavar="N",
                   help="number of blocks (default: the grid's heights, 3 on the lab)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML (default {DEFAULT_CALIBRATION})")
    p.add_argument("--remove-block", type=int, metavar="H",
                   help="fault injection: spawn without the block at height H (1-based), like lab2_spawn.py")
    p.add_argument("--drop-during-move", type=int, metavar="M",
                   help="fault injection: the suction loses its block in the middle of move M's carry (1-based)")
    p.add_argument("--speed", type=_positive_float, default=1.0, metavar="F",
                   help="fraction of the joint speed/acceleration/jerk limits, 0 < F <= 1 (default 1)")
    p.add_argument("--seed", type=int, default=0, metavar="K", help="seed of the suction feedback noise")
    out = p.add_mutually_exclusive_group()
    out.add_argument("--video", metavar="FILE.mp4",
                     help="render an MP4 offscreen (needs imageio + imageio-ffmpeg; headless: MUJOCO_GL=egl)")
    out.add_argument("--frames", metavar="DIR", help="render PNG frames offscreen into DIR (headless: MUJOCO_GL=egl)")
    p.add_argument("--view", action="store_true", help="open MuJoCo's interactive viewer (needs a display)")
    p.add_argument("--json", action="store_true", help="print one JSON object with the outcome on stdout")
    p.set_defaults(func=_run_solve)


def _calibration_path(arg: str | None) -> str:
    """``--calibration`` (a file or a shipped station name), or the shipped default station."""
    return DEFAULT_CALIBRATION if arg is None else arg


def _solve_prompt_tower(what: str, n_towers: int, exclude: int | None = None) -> int:
    """Prompt like the lab program until a valid tower (1-based) is entered; returns it 0-based."""
    choices = " ".join(str(t) for t in range(1, n_towers + 1) if t - 1 != exclude)
    options = choices.rsplit(" ", 1)
    label = f"{options[0]} or {options[1]}" if len(options) == 2 else choices
    while True:
        try:
            text = input(f"Enter the {what} tower <{label}> ")
        except EOFError:
            raise Ur3HanoiError(f"no {what} tower entered (end of input)") from None
        text = text.strip()
        if text.isdigit() and 1 <= int(text) <= n_towers and int(text) - 1 != exclude:
            return int(text) - 1
        print(f"Please just enter the character {label}\n")


def _solve_progress(fraction: float, label: str) -> None:
    width = 30
    filled = round(width * fraction)
    end = "\n" if fraction >= 1.0 else ""
    print(f"\r[{'#' * filled}{'.' * (width - filled)}] {100 * fraction:5.1f}% {label:<12}", end=end,
          file=sys.stderr, flush=True)


def _run_solve(args: argparse.Namespace) -> int:
    import json

    from ur3hanoi.hanoi import validate_instance
    from ur3hanoi.station import load_station

    station = load_station(_calibration_path(args.calibration))
    n_towers = station.n_towers
    n_blocks = station.n_heights if args.blocks is None else args.blocks
    if args.start is None or args.end is None:
        if not sys.stdin.isatty():
            raise Ur3HanoiError("--start and --end are required when stdin is not a terminal "
                                f"(towers 1..{n_towers}), e.g. ur3hanoi solve --start 1 --end 3")
        start = args.start - 1 if args.start is not None else _solve_prompt_tower("start", n_towers)
        end = args.end - 1 if args.end is not None else _solve_prompt_tower("end", n_towers, exclude=start)
    else:
        start, end = args.start - 1, args.end - 1
    validate_instance(n_blocks, start, end, n_towers, station.n_heights)
    if not args.speed <= 1.0:
        raise Ur3HanoiError(f"--speed {args.speed} is invalid: expected 0 < F <= 1")
    n_moves = 2**n_blocks - 1
    if args.remove_block is not None and not 1 <= args.remove_block <= n_blocks:
        raise Ur3HanoiError(f"--remove-block {args.remove_block} is invalid: expected a height 1..{n_blocks}")
    if args.drop_during_move is not None and not 1 <= args.drop_during_move <= n_moves:
        raise Ur3HanoiError(f"--drop-during-move {args.drop_during_move} is invalid: expected a move 1..{n_moves}")
    if (args.video or args.frames) and "MUJOCO_GL" not in os.environ and not os.environ.get("DISPLAY"):
        os.environ["MUJOCO_GL"] = "egl"  # headless offscreen rendering (read when the GL context is created)

    from ur3hanoi.plan import PlanConfig
    from ur3hanoi.sim import (
        Faults,
        OffscreenRecorder,
        SimConfig,
        ViewerSink,
        build_task_scene,
        display_available,
        make_plan,
        run_plan,
    )

    if args.view and display_available() is not None:
        raise Ur3HanoiError(f"--view cannot open the MuJoCo viewer: {display_available()}")
    faults = Faults(
        remove_block=None if args.remove_block is None else args.remove_block - 1,
        drop_during_move=None if args.drop_during_move is None else args.drop_during_move - 1,
    )
    config = SimConfig(seed=args.seed)
    plan = make_plan(station, start, end, n_blocks, PlanConfig(speed=args.speed))
    scene = build_task_scene(station, start, n_blocks, faults.remove_block, config.scene)
    sink: object | None = None
    try:
        if args.view:
            sink = ViewerSink(scene.model, scene.data)
        elif args.video or args.frames:
            sink = OffscreenRecorder(station, scene.model, frames_dir=Path(args.frames) if args.frames else None,
                                     video=Path(args.video) if args.video else None)
        progress = _solve_progress if sys.stderr.isatty() and not args.view else None
        result = run_plan(plan, faults, config, frames=sink, progress=progress,  # type: ignore[arg-type]
                          scene=scene, realtime=args.view)
    finally:
        if sink is not None:
            sink.close()  # type: ignore[attr-defined]

    if args.json:
        print(json.dumps(result.as_dict()))
    else:
        print(f"{result.status}: {result.moves_completed}/{result.moves_total} moves, tower {start + 1} -> "
              f"{end + 1}, {len(result.final_blocks)} blocks on {station.name}")
        for b in result.final_blocks:
            where = f"tower {b.tower + 1} height {b.height + 1}" if b.tower is not None else "in no slot"
            print(f"  block {b.block + 1} ({b.as_dict()['colour']}): {where} at "
                  f"[{b.xyz[0]:.4f}, {b.xyz[1]:.4f}, {b.xyz[2]:.4f}] m")
        print(f"  sim {result.sim_time_s:.2f} s in {result.wall_time_s:.2f} s wall ({result.realtime_factor:.1f}x "
              f"real time), max tracking error {math.degrees(result.max_tracking_error_rad):.3f} deg, suction "
              f"{'on' if result.suction_on_at_end else 'off'}, {'at' if result.at_home_at_end else 'not at'} home")
        if args.video or args.frames:
            print(f"  wrote {sink.count} frames to {args.video or args.frames}")  # type: ignore[union-attr]
    if result.error is not None:
        print(f"ur3hanoi: error: {result.error}", file=sys.stderr)
    return result.exit_code


# ------------------------------------------------------------------------------------------------------- plan


def _add_plan(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("plan", help="solve a Hanoi instance and time-parameterize the motion with Ruckig",
                       description="Solve the Tower of Hanoi from --start to --end (towers and blocks numbered "
                                   "from 1) and plan the whole motion with Ruckig under the UR3's limits "
                                   "(pass-through above the towers, exact vertical approach), checked for "
                                   "joint limits, velocity/acceleration/jerk and clearances.")
    p.add_argument("--start", type=int, required=True, help="start tower (1-based)")
    p.add_argument("--end", type=int, required=True, help="end tower (1-based)")
    p.add_argument("--blocks", type=int, default=None, help="number of blocks (default: the grid's heights)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML (default {DEFAULT_CALIBRATION})")
    p.add_argument("--speed", type=_positive_float, default=1.0,
                   help="scale of the velocity, acceleration and jerk limits, 0 < F <= 1 (default 1)")
    p.add_argument("--rate", type=_positive_float, default=125.0,
                   help="sample rate [Hz]: 125 (CB3, default) or 500 (e-Series); any positive rate is accepted")
    p.add_argument("--dwell", type=float, default=0.3, help="suction dwell at each contact [s] (default 0.3)")
    p.add_argument("--csv", metavar="FILE", help="write t,q1..q6,qd1..qd6,suction samples to FILE (atomic)")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a summary")
    p.add_argument("--no-collision", action="store_true", help="skip the (slower) clearance checks")
    p.set_defaults(func=_run_plan)


def _run_plan(args: argparse.Namespace) -> int:
    import json

    from ur3hanoi.plan import PlanConfig, plan_solve, trajectory_csv
    from ur3hanoi.station import load_station
    from ur3hanoi.table import atomic_write

    station = load_station(_calibration_path(args.calibration))
    n_blocks = station.n_heights if args.blocks is None else args.blocks
    config = PlanConfig(speed=args.speed, rate_hz=args.rate, dwell_s=args.dwell,
                        check_collisions=not args.no_collision)
    plan = plan_solve(station, args.start - 1, args.end - 1, n_blocks, config)
    if args.csv:
        atomic_write(args.csv, trajectory_csv(plan.trajectory))
    if args.json:
        print(json.dumps(plan.to_json_dict()))
        return 0
    print(f"{station.name}: {n_blocks} blocks, tower {args.start} -> {args.end}: {len(plan.moves)} moves")
    for i, m in enumerate(plan.moves, start=1):
        d = m.as_lab_dict()
        print(f"  {i:>3}. block {d['block']}: tower {d['from_tower']} height {d['from_height']} -> "
              f"tower {d['to_tower']} height {d['to_height']}")
    print(f"cycle {plan.duration_s:.3f} s (motion {plan.motion_s:.3f} s), stop-and-go {plan.stop_and_go_duration_s:.3f}"
          f" s (motion {plan.stop_and_go_motion_s:.3f} s): {100 * plan.motion_saving:.1f} % less motion time")
    print(f"{len(plan.trajectory.t)} samples at {plan.trajectory.rate_hz:g} Hz, speed {args.speed:g}; all limit and "
          "clearance checks passed" + (f"; wrote {args.csv}" if args.csv else ""))
    return 0


# ------------------------------------------------------------------------------------------------------- main

_COMMANDS = [_add_tables, _add_check_table, _add_calibrate, _add_plan, _add_solve, add_ros_commands]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ur3hanoi", description="UR3 Tower of Hanoi lab toolkit.")
    parser.add_argument("--version", action="version", version=f"ur3hanoi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in _COMMANDS:
        add(sub)
    return parser


def help_markdown(width: int = 100) -> str:
    """The README's CLI reference: ``--help`` of the command and of every subcommand, at a fixed width."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)  # argparse wraps to the terminal width: pin it for a stable text
    try:
        parser = build_parser()
        parts = ["```text", "$ ur3hanoi --help", parser.format_help().rstrip(), "```"]
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        for name, p in sub.choices.items():
            parts += ["", f"#### `ur3hanoi {name}`", "", "```text", p.format_help().rstrip(), "```"]
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return "\n".join(parts) + "\n"


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except Ur3HanoiError as exc:
        print(f"ur3hanoi: error: {' '.join(str(exc).split())}", file=sys.stderr)
        return exc.exit_code
    except KeyboardInterrupt:
        print("ur3hanoi: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
