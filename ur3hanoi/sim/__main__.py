"""``python -m ur3hanoi.sim [OUT_DIR]``: regenerate ``ur3.xml`` and ``assets/`` from the URDF.

Without ``OUT_DIR`` it rewrites the package's own robot folder (``robots/universal_robots_ur3``); a test checks
that the committed files equal what this writes.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

from ur3hanoi.sim.model import ROBOT_DIR, SOURCE_PACKAGE, write_ur3_files


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m ur3hanoi.sim",
                                     description=f"Derive the MuJoCo UR3 (ur3.xml + assets/) from {SOURCE_PACKAGE}'s "
                                                 "ur3_robot.urdf.")
    parser.add_argument("out_dir", nargs="?", type=Path, default=ROBOT_DIR,
                        help=f"robot folder to write (default: {ROBOT_DIR})")
    args = parser.parse_args(argv)
    for path in write_ur3_files(args.out_dir):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
