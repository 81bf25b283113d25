"""ur3hanoi: kinematics toolkit for the UR3 Tower of Hanoi lab.

Modules, one concept each: :mod:`~ur3hanoi.robot.model` (UR3 model, frames, limits),
:mod:`~ur3hanoi.station.calibration` (calibration files), :mod:`~ur3hanoi.station.grid` (Cartesian tower grid),
:mod:`~ur3hanoi.robot.ik` (inverse kinematics),
:mod:`~ur3hanoi.tables.ik_table` (the joint table by IK), :mod:`~ur3hanoi.tables` (``lab2_data.yaml``),
:mod:`~ur3hanoi.calibrate.taught` and :mod:`~ur3hanoi.calibrate` (calibration from taught poses), :mod:`~ur3hanoi.io`
(the one YAML loader, schemas, the one atomic writer), :mod:`~ur3hanoi.io.cache` (the user's cache of derived data),
:mod:`~ur3hanoi.cli` (the ``ur3hanoi`` command).
"""

__version__ = "0.1.0"
