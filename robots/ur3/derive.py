#!/usr/bin/env python3
"""Regenerate robots/ur3/ur3.xml and robots/ur3/assets/*.stl from example-robot-data's ur3_robot.urdf.

Usage (from the repository root): .venv/bin/python robots/ur3/derive.py

The derivation is deterministic (ur3hanoi.sim.derive_ur3_mjcf); tests/test_sim.py fails when the committed
ur3.xml differs from what this script writes. scene.xml is hand-written and not touched.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from ur3hanoi.sim import ROBOT_DIR, write_ur3_files


def main() -> int:
    for path in write_ur3_files(ROBOT_DIR):
        print(f"wrote {path.relative_to(ROBOT_DIR.parents[1])}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
