"""``ur3hanoi check-table``: audit every entry of a lab table against a calibration, or against the grid fitted to
the table itself (``--fit``); see :mod:`ur3hanoi.audit`."""

from __future__ import annotations

import argparse

from ur3hanoi.cli import exit_codes
from ur3hanoi.cli.options import TABLE_KEYS, TOL_DEG, TOL_MM, UsageError, option


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-table", help="audit a lab-format table: against a calibration, or its own fitted grid",
                       description="Report, for every Q[tower][height][k] of FILE, how far its suction point [mm] "
                                   "and axis [deg] are from a reference, the missing entries, and the flagged "
                                   "entries worst first with what probably happened (a typo in one joint, swapped or "
                                   "copied entries). The reference is a calibration's intended poses (--calibration; "
                                   "default tolerance 1 mm / 0.5 deg, for generated tables) or the station grid "
                                   "fitted robustly to the table's own contacts (--fit, for hand-recorded tables): a "
                                   "contact within 5 mm of its tower's line and its level, axis within 4 deg of the "
                                   "table's, is never flagged; more than 8 mm from where the fit puts it or 5 deg "
                                   "tilted always is; in between at most a warning; the heading about the suction "
                                   "axis is never judged; an above pose must be 10 mm over the top level (flagged "
                                   "under 5 mm) and within 8 mm of its contact's line (flagged over 10 mm). Towers "
                                   "and heights are numbered from 1. Exit 1 if any entry is flagged.")
    p.add_argument("file", help="lab-format YAML (generated or hand-recorded; null or left-out entries allowed)")
    p.add_argument("--key", required=True, choices=TABLE_KEYS, help="table key")
    ref = p.add_mutually_exclusive_group(required=True)
    ref.add_argument("--calibration", help="station calibration YAML, or a shipped station name: check against its "
                                           "intended poses")
    ref.add_argument("--fit", action="store_true",
                     help="audit the table on its own: fit the station grid to its entries robustly")
    p.add_argument("--base", metavar="CALIBRATION",
                   help="with --fit: the calibration giving robot base, tool and home (default lab_sim for "
                        "sim_pos, lab_real for real_pos; the layout, flat or stacked, is read off the table)")
    p.add_argument("--tol-mm", type=option(TOL_MM), default=None,
                   help=f"{TOL_MM.expected()} (default 1 with --calibration; with --fit it replaces the 8 mm a "
                        "contact is flagged over)")
    p.add_argument("--tol-deg", type=option(TOL_DEG), default=None,
                   help=f"{TOL_DEG.expected()} (default 0.5 with --calibration; with --fit it replaces the 5 deg "
                        "a contact's axis is flagged over)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object: entries, suspects, warnings, fit (with --fit: the rule's thresholds)")
    p.add_argument("--plot", metavar="FILE",
                   help="draw the audit into FILE (.png, .svg or .pdf): top and side views of the recorded suction "
                        "points against where the audit puts them, flagged entries marked and labelled, warned ones "
                        "in orange (needs the plot extra)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import json

    from ur3hanoi.audit import STRICT_DEG, STRICT_MM, audit_table, check_against, default_base
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.tables import read_recorded_table

    if args.base is not None and not args.fit:
        raise UsageError("--base is only used with --fit")
    if args.plot:
        from pathlib import Path

        from ur3hanoi.plots import check_plot_path, require_matplotlib

        require_matplotlib()
        check_plot_path(args.plot, (Path(args.file),))  # before the audit's work
    table = read_recorded_table(args.file, args.key)
    if args.fit:
        base = load_station(args.base or default_base(args.key))
        report = audit_table(table, base, args.tol_mm, args.tol_deg)
    else:
        station = load_station(args.calibration)
        tol_mm = STRICT_MM if args.tol_mm is None else args.tol_mm
        tol_deg = STRICT_DEG if args.tol_deg is None else args.tol_deg
        report = check_against(table, station, tol_mm, tol_deg)
    if args.plot:
        from ur3hanoi.plots.audit import write_audit_plot

        write_audit_plot(args.plot, report, title=f"{table.source}: {report.reference}", inputs=(Path(args.file),))
    print(json.dumps(report.to_json()) if args.json else report.text())
    return exit_codes.OVER_TOLERANCE if report.failed else exit_codes.OK
