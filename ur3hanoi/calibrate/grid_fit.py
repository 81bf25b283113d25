"""The tower grid as a linear model of measured suction points, its least-squares fit and leave-one-out deviations.

Model (world frame, [m])::

    contact point (tower t, height h)  = o_t + h * s
    above point   (tower t, height h)  = o_t + h * s + a * z_world

with one origin ``o_t`` per tower, one height step ``s`` shared by all towers and one approach height ``a``. The
unknowns are solved by linear least squares (``numpy.linalg.lstsq``) on the suction-point positions measured by
forward kinematics (:func:`measure`). ``s`` is fitted only when the points determine it (some tower measured at two
different heights; only its x and y for a ``flat`` layout, whose step is horizontal); otherwise it is the default
of :func:`default_height_step`. ``a`` is fitted only when above poses are used.

The deviation of a point from the grid fitted to the *other* points (leave one out) comes in closed form from the
3x3 diagonal block ``H_ii`` of the hat matrix: ``e_(i) = (I - H_ii)^-1 e_i``. A point that alone determines some
unknown (``I - H_ii`` singular) has no such deviation: it cannot be checked, and it cannot be left out.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ur3hanoi.arrays import FloatArray
from ur3hanoi.robot.model import load_ur3
from ur3hanoi.station.calibration import Station
from ur3hanoi.station.grid import ABOVE, R_world_tcp_down
from ur3hanoi.tables import Slot

BoolArray = npt.NDArray[np.bool_]

_SINGULAR = 1e-9  # smallest eigenvalue of I - H_ii for a point that can be left out
FLAT_STEP_PASSES = 60
"""At most this many fixed-point passes turn a flat layout's unfitted step with its tower row (:func:`solve`)."""


@dataclass(frozen=True)
class Measured:
    """Forward kinematics of N joint poses in a station's world frame.

    Attributes:
        p_world: suction points (TCP), shape (N, 3) [m, world].
        R_world: TCP orientations, shape (N, 3, 3).
        heading: direction of the TCP x axis in the world xy plane, shape (N,) [rad].
        tilt_deg: angle of the TCP z axis from straight down, shape (N,) [deg].
    """

    p_world: FloatArray
    R_world: FloatArray
    heading: FloatArray
    tilt_deg: FloatArray


def measure(station: Station, qs: Sequence[Sequence[float]]) -> Measured:
    """FK of joint poses ``qs`` [rad] with ``station``'s robot base and tool."""
    robot = load_ur3(station.tool, station.limits, station.robot)
    T_wb = station.T_world_base
    n = len(qs)
    p, R = np.empty((n, 3)), np.empty((n, 3, 3))
    for i, q in enumerate(qs):
        T = T_wb * robot.fk(np.asarray(q, dtype=float), "tcp")
        p[i], R[i] = T.translation, T.rotation
    heading = np.arctan2(R[:, 1, 0], R[:, 0, 0])
    tilt = np.degrees(np.arccos(np.clip(-R[:, 2, 2], -1.0, 1.0)))
    return Measured(p_world=p, R_world=R, heading=heading, tilt_deg=tilt)


def rotation_error_deg(R_world: FloatArray, yaw: float) -> FloatArray:
    """Angle [deg] between each orientation (N, 3, 3) and the grid's TCP orientation (pointing down at ``yaw``)."""
    R_grid = R_world_tcp_down(yaw)
    return np.array([math.degrees(float(np.linalg.norm(pin.log3(R_grid.T @ R)))) for R in R_world])


def circular_mean(angles: FloatArray) -> float:
    """Mean direction [rad] of ``angles`` [rad] (headings either side of +-180 deg average correctly)."""
    return math.atan2(float(np.mean(np.sin(angles))), float(np.mean(np.cos(angles))))


def _rot_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def default_height_step(base: Station, origins: FloatArray | None) -> FloatArray:
    """Height step [m, world] when the points do not determine it.

    One block size along world +z for a ``stacked`` base layout; for a ``flat`` one the base's height step turned
    about world z by the angle between the base's tower row (first tower -> last tower) and the fitted one
    (``origins`` (T, 3) [m]; None: unturned), so rows keep their angle to the tower row.
    """
    if base.layout == "stacked":
        return np.array([0.0, 0.0, base.block_size])
    if origins is None or len(origins) < 2 or base.n_towers < 2:
        return np.asarray(base.height_step, dtype=float)
    row_base = np.subtract(base.tower_origins[-1], base.tower_origins[0])
    row_fit = origins[-1] - origins[0]
    turn = math.atan2(row_fit[1], row_fit[0]) - math.atan2(row_base[1], row_base[0])
    return _rot_z(turn) @ np.asarray(base.height_step, dtype=float)


@dataclass(frozen=True)
class GridModel:
    """Which grid parameters a fit solves for.

    Attributes:
        n_towers: number of tower origins.
        step_axes: world axes of the height step that are fitted (``()``: the default step is used).
        fit_approach: whether the approach height is fitted (above poses are used).
    """

    n_towers: int
    step_axes: tuple[int, ...]
    fit_approach: bool

    @property
    def n_unknowns(self) -> int:
        return 3 * self.n_towers + len(self.step_axes) + (1 if self.fit_approach else 0)

    @property
    def params(self) -> tuple[str, ...]:
        """Names of the fitted station parameters (the tool yaw is always fitted, from the headings)."""
        names = ["tower_origins"]
        if self.step_axes:
            names.append("height_step")
        names.append("tool_yaw")
        if self.fit_approach:
            names.append("approach")
        return tuple(names)

    def design(self, slots: Sequence[Slot]) -> FloatArray:
        """Model matrix: 3 rows (x, y, z) per slot; columns o_0..o_T-1, the fitted step axes, then a."""
        S = np.asarray(slots, dtype=int).reshape(-1, 3)
        rows = 3 * np.arange(len(S))
        A = np.zeros((3 * len(S), self.n_unknowns))
        for axis in range(3):
            A[rows + axis, 3 * S[:, 0] + axis] = 1.0
        for c, axis in enumerate(self.step_axes):
            A[rows + axis, 3 * self.n_towers + c] = S[:, 1]
        if self.fit_approach:
            A[rows[S[:, 2] == ABOVE] + 2, -1] = 1.0
        return A

    def determined_by(self, slots: Sequence[Slot]) -> bool:
        """True when ``slots`` determine every unknown of this model."""
        return bool(slots) and int(np.linalg.matrix_rank(self.design(slots))) == self.n_unknowns


def choose_model(base: Station, slots: Sequence[Slot]) -> GridModel | None:
    """The fullest model ``slots`` determine (step fitted if possible), or None if even the origins are not."""
    fit_approach = any(k == ABOVE for _, _, k in slots)
    axes: tuple[int, ...] = (0, 1) if base.layout == "flat" else (0, 1, 2)
    for step_axes in (axes, ()):
        model = GridModel(base.n_towers, step_axes, fit_approach)
        if model.determined_by(slots):
            return model
    return None


@dataclass(frozen=True)
class GridSolution:
    """A fitted grid: ``origins`` (T, 3), ``step`` (3,) [m, world], ``approach`` [m]."""

    origins: FloatArray
    step: FloatArray
    approach: float

    def point(self, slot: Slot) -> FloatArray:
        """The grid's suction point [m, world] for ``(tower, height, k)``."""
        t, h, k = slot
        p = self.origins[t] + h * self.step
        return p + np.array([0.0, 0.0, self.approach]) if k == ABOVE else p

    def points(self, slots: Sequence[Slot]) -> FloatArray:
        """:meth:`point` of each slot, shape (N, 3) [m, world]."""
        S = np.asarray(slots, dtype=int).reshape(-1, 3)
        p = self.origins[S[:, 0]] + S[:, 1:2] * self.step
        p[S[:, 2] == ABOVE, 2] += self.approach
        return p


def _lstsq(A: FloatArray, b: FloatArray) -> FloatArray:
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    return np.asarray(x, dtype=float)


def _fixed_part(slots: Sequence[Slot], step: FloatArray) -> FloatArray:
    heights = np.asarray(slots, dtype=int).reshape(-1, 3)[:, 1]
    return (heights[:, None] * step).reshape(-1)


def solve(base: Station, model: GridModel, slots: Sequence[Slot], p_world: FloatArray,
          design: FloatArray | None = None) -> GridSolution:
    """Least-squares grid of ``model`` through the points ``p_world`` (N, 3) [m] measured at ``slots``.

    ``slots`` must determine the model (:meth:`GridModel.determined_by`); ``design`` is ``model.design(slots)``
    when already at hand.
    """
    n_t = model.n_towers
    A = model.design(slots) if design is None else design
    b = p_world.reshape(-1)
    if model.step_axes:
        x = _lstsq(A, b)
        step = np.zeros(3)
        step[list(model.step_axes)] = x[3 * n_t:3 * n_t + len(model.step_axes)]
    else:
        # A flat layout's default step turns with the fitted tower row, which itself depends on the step through
        # any points above height 0: fixed-point passes settle it (one pass is exact for height-0 points; a tower
        # taught two rows up on a row 100 mm from the base's shrinks the change by only a third a pass).
        step = default_height_step(base, None)
        for _ in range(FLAT_STEP_PASSES):
            x = _lstsq(A, b - _fixed_part(slots, step))
            new = default_height_step(base, x[:3 * n_t].reshape(n_t, 3))
            settled = float(np.max(np.abs(new - step))) < 1e-13
            step = new
            if settled:
                break
    approach = float(x[-1]) if model.fit_approach else base.approach
    return GridSolution(origins=x[:3 * n_t].reshape(n_t, 3), step=step, approach=approach)


def _leave_one_out_blocks(model: GridModel, slots: Sequence[Slot]) -> list[FloatArray | None]:
    """Per point, ``I - H_ii`` (the 3x3 diagonal block of the hat matrix taken from the identity), or None when it
    is singular: the point alone determines some unknown."""
    A = model.design(slots)
    inv = np.linalg.pinv(A.T @ A)
    out: list[FloatArray | None] = []
    for i in range(len(slots)):
        Ai = A[3 * i:3 * i + 3]
        M = np.eye(3) - Ai @ inv @ Ai.T
        out.append(M if float(np.min(np.linalg.eigvalsh(0.5 * (M + M.T)))) > _SINGULAR else None)
    return out


def removable(model: GridModel, slots: Sequence[Slot]) -> BoolArray:
    """Per point of ``slots`` (which determine ``model``): True when the others determine the grid without it, so
    that it can be checked against them; False when it alone determines some unknown (the only point of its tower,
    say): the audit calls such a point ``unchecked``. Depends on the slots only, not on the measurements."""
    return np.array([m is not None for m in _leave_one_out_blocks(model, slots)], dtype=bool)


def leave_one_out(model: GridModel, slots: Sequence[Slot], p_world: FloatArray, solution: GridSolution
                  ) -> tuple[FloatArray, BoolArray]:
    """Deviation of each point from the grid fitted to the others, for the points ``solution`` was fitted to.

    Returns:
        (deviations (N, 3) [m, world], NaN rows where undefined; removable (N,), False for a point that alone
        determines some unknown, :func:`removable`). A default (unfitted) height step is held at its fitted value.
    """
    n = len(slots)
    residual = p_world - solution.points(slots)
    out = np.full((n, 3), np.nan)
    can = np.zeros(n, dtype=bool)
    for i, M in enumerate(_leave_one_out_blocks(model, slots)):
        if M is not None:
            out[i] = np.linalg.solve(M, residual[i])
            can[i] = True
    return out, can


__all__ = [
    "FLAT_STEP_PASSES",
    "GridModel",
    "GridSolution",
    "Measured",
    "choose_model",
    "circular_mean",
    "default_height_step",
    "leave_one_out",
    "measure",
    "removable",
    "rotation_error_deg",
    "solve",
]
