"""``ur3hanoi calibrate``: fit a station's tower grid to taught poses and write the new calibration."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

from ur3hanoi.cli.common import SYMLINK_NOTE, input_file, shown
from ur3hanoi.cli.options import ACCEPT_HELP, TABLE_KEYS, UsageError, check_accept, slot
from ur3hanoi.errors import printable, quote


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("calibrate", help="fit a station's tower grid to taught poses (robust least squares)",
                       description="Fit the tower origins, height step, approach and tool yaw of a station to "
                                   "taught joint poses (or to every entry present in a lab-format table); "
                                   "everything else comes from --base. A gross error (the home pose, a pose in "
                                   "the wrong slot, a typo in one joint, copied entries) is found by what explains "
                                   "the most: the point whose removal leaves the others consistent with each "
                                   "other, one flat table, the block size and the tool pointing down; it is named "
                                   "and left out. When it is its tower's only contact, or the points cannot tell "
                                   "which of two is wrong, nothing is written (exit 2) and the message says which "
                                   "and what to do. The towers stand wherever the points put them; a tower taught "
                                   "at one pose is written, and the output says that nothing checks where it "
                                   "stands along the table. The report gives every point's deviation [mm] and the "
                                   "suspects worst first. Towers and heights are numbered from 1. See "
                                   "`ur3hanoi.calibrate.taught` for the file format.")
    src = p.add_mutually_exclusive_group(required=True)
    src.add_argument("--taught", metavar="FILE", help="taught-points YAML (units: deg|rad; points: [...])")
    src.add_argument("--from-table", metavar="FILE", help="lab-format table whose entries are the taught points")
    p.add_argument("--key", choices=TABLE_KEYS, help="table key with --from-table")
    p.add_argument("--base", required=True, metavar="CALIBRATION",
                   help="station calibration providing robot base, tool, blocks, home, counts and layout")
    p.add_argument("-o", "--output", required=True, metavar="OUT",
                   help=f"calibration YAML to write ({SYMLINK_NOTE}; never one of the inputs)")
    p.add_argument("--name", help="station name written to OUT (default: OUT's file name without extension)")
    p.add_argument("--accept", type=slot, action="append", metavar="T,H", help=ACCEPT_HELP)
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (entries, suspects, fit) instead of the report; messages go to "
                        "stderr")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import json

    from ur3hanoi.audit import audit_taught
    from ur3hanoi.calibrate import fit_station, write_calibration
    from ur3hanoi.calibrate.taught import load_taught, taught_from_recorded
    from ur3hanoi.calibrate.verdict import note_lines
    from ur3hanoi.io.atomic import check_output
    from ur3hanoi.io.schema import Text
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.tables import read_recorded_table

    if args.from_table is not None and args.key is None:
        raise UsageError(f"--from-table needs --key ({' or '.join(TABLE_KEYS)})")
    if args.taught is not None and args.key is not None:
        raise UsageError("--key is only used with --from-table")
    name_spec = Text(max_len=255)
    if args.name is not None and not name_spec.accepts(args.name):
        raise UsageError(f"--name {quote(args.name)} is invalid: expected {name_spec.expected()}")
    inputs = [input_file(args.base), Path(args.taught or args.from_table)]
    check_output(args.output, inputs=inputs)
    out = Path(args.output)
    base = load_station(args.base)
    shared: tuple[tuple[int, tuple[int, ...]], ...] = ()
    if args.taught is not None:
        taught = load_taught(args.taught)
        taught_label = Path(args.taught).as_posix()
    else:
        table = read_recorded_table(args.from_table, args.key)
        taught, shared = taught_from_recorded(table), table.shared_above
        taught_label = f"{Path(args.from_table).as_posix()} key {args.key}"
    contacts = {(p.tower, p.height) for p in taught.points if p.k == 0}
    accept = check_accept(args.accept, contacts, taught_label)
    fit = fit_station(base, taught, name=args.name or printable(out.stem, name_spec.max_len), source=str(args.output),
                      accept=accept)
    report = audit_taught(fit, taught, args.key or "Q", shared)
    notes = note_lines(fit.points, fit.accepted, fit.single_pose, Path(args.base).as_posix())
    print(json.dumps(_with_notes(report.to_json(), fit, notes)) if args.json else report.text())
    sys.stdout.flush()
    # An unsound fit is refused here with one error line (the report above names the suspects).
    write_calibration(out, fit, taught, base, taught_label=taught_label, base_label=Path(args.base).as_posix(),
                      inputs=inputs)
    for w in fit.warnings:
        print(f"ur3hanoi: warning: {w}", file=sys.stderr)
    for line in notes:
        print(line, file=sys.stderr if args.json else sys.stdout)
    exact = " (exact fit: add points to check it)" if fit.dof == 0 else ""
    left_out = len(fit.points) - fit.n_used
    print(f"wrote {shown(args.output)}: fitted {', '.join(fit.fitted_params)} from {fit.n_used} of "
          f"{len(fit.points)} points ({left_out} suspect left out), residual rms {fit.rms_mm:.3f} mm, max "
          f"{fit.max_mm:.3f} mm{exact}; {len(fit.suspects)} suspect(s)", file=sys.stderr if args.json else sys.stdout)
    return 0


def _with_notes(report: dict[str, Any], fit: Any, notes: list[str]) -> dict[str, Any]:
    """The audit's JSON with what the calibration rests on unchecked: ``single_pose`` (per tower resting on one
    pose: its number from 1, the pose's field, the pose that would check it) and ``notes`` (the lines printed)."""
    from ur3hanoi.station.grid import ABOVE, pose_label

    report["single_pose"] = [{"tower": t + 1, "pose": fit.points[i].where,
                              "check_with": pose_label(t, fit.points[i].height, ABOVE),
                              "axis_from_other_towers_deg": None if lean != lean else round(float(lean), 3)}
                             for t, i, lean in fit.single_pose]
    report["notes"] = notes
    return report
