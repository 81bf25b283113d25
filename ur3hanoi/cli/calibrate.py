"""``ur3hanoi calibrate``: fit a station's tower grid to taught poses and write the new calibration."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ur3hanoi.cli.common import SYMLINK_NOTE, input_file, shown
from ur3hanoi.cli.options import UsageError
from ur3hanoi.errors import printable, quote
from ur3hanoi.io.schema import Text
from ur3hanoi.labfile import TABLE_KEYS

_NAME = Text(max_len=255)


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="fit a station's tower grid to taught poses (least squares)",
                       description="Fit the tower origins, height step, approach and tool yaw of a station to "
                                   "taught joint poses (or to every entry of an existing lab-format table); "
                                   "everything else comes from --base. Prints the residual of every point [mm] "
                                   "and warns about points over 2 mm. See `ur3hanoi.taught` for the format.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--taught", metavar="FILE", help="taught-points YAML (units: deg|rad; points: [...])")
    src.add_argument("--from-table", metavar="FILE", help="lab-format table whose entries are the taught points")
    p.add_argument("--key", choices=TABLE_KEYS, help="table key with --from-table")
    p.add_argument("--base", required=True, metavar="CALIBRATION",
                   help="station calibration providing robot base, tool, blocks, home, counts and layout")
    p.add_argument("-o", "--output", required=True, metavar="OUT",
                   help=f"calibration YAML to write ({SYMLINK_NOTE}; never one of the inputs)")
    p.add_argument("--name", help="station name written to OUT (default: OUT's file name without extension)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ur3hanoi.calibrate import fit_station, write_calibration
    from ur3hanoi.io.atomic import check_output
    from ur3hanoi.station import load_station
    from ur3hanoi.taught import load_taught, taught_from_table

    if args.from_table is not None and args.key is None:
        raise UsageError(f"--from-table needs --key ({' or '.join(TABLE_KEYS)})")
    if args.taught is not None and args.key is not None:
        raise UsageError("--key is only used with --from-table")
    if args.name is not None and not _NAME.accepts(args.name):
        raise UsageError(f"--name {quote(args.name)} is invalid: expected {_NAME.expected()}")
    inputs = [input_file(args.base), Path(args.taught or args.from_table)]
    check_output(args.output, inputs=inputs)
    out = Path(args.output)
    base = load_station(args.base)
    if args.taught is not None:
        taught = load_taught(args.taught)
        taught_label = Path(args.taught).as_posix()
    else:
        taught = taught_from_table(args.from_table, args.key)
        taught_label = f"{Path(args.from_table).as_posix()} key {args.key}"
    fit = fit_station(base, taught, name=args.name or printable(out.stem, _NAME.max_len), source=str(args.output))
    write_calibration(out, fit, taught, base, taught_label=taught_label, base_label=Path(args.base).as_posix(),
                      inputs=inputs)

    print(f"{'point':>6} {'tower':>5} {'height':>6} {'pose':>5} {'res [mm]':>9} {'dx':>7} {'dy':>7} {'dz':>7} "
          f"{'yaw [deg]':>9} {'tilt':>6}")
    for r in fit.residual_table():
        print(f"{r.index:>6} {r.tower:>5} {r.height:>6} {r.pose:>5} {r.residual_mm:>9.3f} {r.dx_mm:>7.3f} "
              f"{r.dy_mm:>7.3f} {r.dz_mm:>7.3f} {r.yaw_dev_deg:>9.3f} {r.tilt_deg:>6.2f}{'  <-' if r.flagged else ''}")
    for w in fit.warnings:
        print(f"ur3hanoi: warning: {w}", file=sys.stderr)
    exact = " (exact fit: add points to check it)" if fit.dof == 0 else ""
    print(f"wrote {shown(args.output)}: fitted {', '.join(fit.fitted_params)} from {len(fit.points)} points, "
          f"residual rms {fit.rms_mm:.3f} mm, max {fit.max_mm:.3f} mm{exact}; {len(fit.warnings)} warning(s)")
    return 0
