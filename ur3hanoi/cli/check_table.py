"""``ur3hanoi check-table``: FK of every entry of a lab table against a calibration's intended poses."""

from __future__ import annotations

import argparse

from ur3hanoi.cli import exit_codes
from ur3hanoi.cli.options import TOL_DEG, TOL_MM, option
from ur3hanoi.labfile import TABLE_KEYS


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check-table", help="FK-check every entry of a lab-format table against a calibration",
                       description="Report, for every Q[tower][height][k] of FILE, the FK position [mm] and "
                                   "orientation [deg] error of the suction point against the calibration's "
                                   "intended pose; exit 1 if any entry exceeds the tolerance.")
    p.add_argument("file", help="lab-format YAML (generated or hand-recorded)")
    p.add_argument("--key", required=True, choices=TABLE_KEYS, help="table key")
    p.add_argument("--calibration", required=True, help="station calibration YAML, or a shipped station name")
    p.add_argument("--tol-mm", type=option(TOL_MM), default=1.0,
                   help=f"{TOL_MM.expected()} (default 1)")
    p.add_argument("--tol-deg", type=option(TOL_DEG), default=0.5,
                   help=f"{TOL_DEG.expected()} (default 0.5)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ur3hanoi.labfile import read_table
    from ur3hanoi.station import load_station
    from ur3hanoi.waypoints import check_table

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
    return exit_codes.OVER_TOLERANCE if bad else exit_codes.OK
