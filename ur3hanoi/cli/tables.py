"""``ur3hanoi tables``: generate a lab table key from a calibration by IK and write it into the lab file."""

from __future__ import annotations

import argparse
from pathlib import Path

from ur3hanoi.cli.common import SYMLINK_NOTE, input_file, shown
from ur3hanoi.cli.options import TABLE_KEYS


def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("tables", help="generate a lab2_data.yaml waypoint table from a calibration by IK",
                       description="Generate Q[tower][height][0 = on, 1 = above] (6 joint angles [rad]) by IK "
                                   "and write it under --key into FILE, keeping every other key of FILE.")
    p.add_argument("calibration", help="station calibration YAML, or a shipped station name (lab_sim, lab_real)")
    p.add_argument("--key", required=True, choices=TABLE_KEYS, help="table key to (re)generate")
    p.add_argument("-o", "--output", required=True, metavar="FILE",
                   help=f"lab-format YAML file to create/update ({SYMLINK_NOTE}; concurrent runs are serialized)")
    p.add_argument("--solver", default="pinocchio", choices=["pinocchio", "placo"],
                   help="IK refiner, used where the closed form misses a pose by more than 1e-9 m or 1e-9 rad")
    p.add_argument("--convention", default="controller", choices=["controller", "course"],
                   help="joint convention of the written angles: controller (the pendant's, default) or course (the "
                        "ROS 2 course bridge's: controller - [pi/2, 0, 0, -pi/2, 0, 0]); named in the key's header")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    print(write_key(args.calibration, args.key, args.output, args.solver, args.convention))
    return 0


def write_key(calibration: str, key: str, output: str, solver: str = "pinocchio", convention: str = "controller"
              ) -> str:
    """Generate ``key`` from ``calibration`` by IK and write it into the lab file ``output``, keeping every other
    key (``tables -o``, and ``teach --table``); returns the line that says what was written."""
    from ur3hanoi.io.atomic import check_output
    from ur3hanoi.station.calibration import load_station
    from ur3hanoi.tables.ik_table import generate_table
    from ur3hanoi.tables.write import write_table

    inputs = [input_file(calibration)]
    check_output(output, inputs=inputs)  # fail before the IK, not after
    # An output file that is not YAML, or not a mapping of keys, is refused by the write before it writes (the IK of
    # a table takes about a millisecond: reading the file twice would cost more than it saves).
    station = load_station(calibration)
    table = generate_table(station, solver)
    write_table(output, table, key, Path(calibration).as_posix(), inputs=inputs, convention=convention)
    refined = sum(r.iterations > 0 for r in table.results)
    return (f"wrote {key} ({station.n_towers} towers x {station.n_heights} heights x 2) to {shown(output)}: "
            f"max IK error {table.max_position_error:.2e} m, {table.max_orientation_error:.2e} rad (closed form, "
            f"{refined} of {len(table.results)} poses refined by {table.solver})")
