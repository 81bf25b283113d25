"""The station: a calibrated lab layout (robot base, tool, tower grid, blocks, home, suction feedback levels).

- :mod:`~ur3hanoi.station.calibration`: the calibration file (``Station``), read and validated.
- :mod:`~ur3hanoi.station.grid`: the Cartesian tower grid: suction-point targets and pose labels.
- :mod:`~ur3hanoi.station.suction_profile`: the suction feedback levels (DIGIN, AIN0) of a station.

Data: ``shipped/`` holds the shipped calibrations (``lab_sim``, ``lab_real``, ``ur3e_sim``) and their reference.
"""
