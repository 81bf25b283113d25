"""The one array alias of ur3hanoi: joint vectors, positions and samples are ``float64`` NumPy arrays."""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

FloatArray = npt.NDArray[np.float64]
"""A ``float64`` array; shapes and units are given where it is used (``q`` (6,) [rad], ``p_world`` (3,) [m])."""
