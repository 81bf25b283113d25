"""The ``ur3hanoi`` command line. Every user error prints one line ``ur3hanoi: error: ...`` and exits non-zero
(2 for bad input or unreachable poses, 3 for a suction fault); no output file is left half-written.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi import __version__
from ur3hanoi.errors import Ur3HanoiError

DEFAULT_CALIBRATION = "robots/stations/lab_sim.yaml"


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
    p.add_argument("calibration", help="station calibration YAML (e.g. robots/stations/lab_sim.yaml)")
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


# ------------------------------------------------------------------------------------------------------- main

_COMMANDS = [_add_tables, _add_check_table, _add_calibrate]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="ur3hanoi", description="UR3 Tower of Hanoi lab toolkit.")
    parser.add_argument("--version", action="version", version=f"ur3hanoi {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for add in _COMMANDS:
        add(sub)
    return parser


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
