"""Calibrate a real station's tower grid from a few taught poses (joint angles recorded on the teach pendant).

Workflow::

    ur3hanoi calibrate --taught my_taught.yaml --base lab_real -o my_station.yaml
    ur3hanoi tables my_station.yaml --key real_pos -o lab2_data.yaml

or, from an existing (e.g. hand-recorded) lab-format table, every entry ``Q[t][h][k]`` used as a taught point::

    ur3hanoi calibrate --from-table lab2_data.yaml --key real_pos --base lab_real -o out.yaml

The taught-points file and its checks are :mod:`ur3hanoi.taught`.

What is fitted, and how. Each pose's suction point (TCP) is computed by forward kinematics, in the station's world
frame (``T_world_base * fk(q, "tcp")``, with the base calibration's robot base and tool offset). The grid model is

    contact point (tower t, height h)  = o_t + h * s
    above point   (tower t, height h)  = o_t + h * s + a * z_world

with one origin ``o_t`` per tower (explicit ``tower_origins``: real towers are rarely evenly spaced), one height
step ``s`` shared by all towers and one approach height ``a``. The unknowns are solved by linear least squares
(``numpy.linalg.lstsq``) on the suction-point positions:

- ``o_t`` always (every tower needs at least one taught point);
- ``s`` only when the points determine it (some tower taught at two different heights). Otherwise it is the
  default: one block size along world +z for a ``stacked`` base layout; for a ``flat`` base layout the base's
  height step, rotated about world z by the angle between the base's tower row (tower 0 -> last tower) and the
  fitted one, so rows stay at the same angle to the tower row. For a ``flat`` layout ``s`` is horizontal by
  definition, so only its x and y are fitted;
- ``a`` only when above poses are given (else the base's approach).

The tool yaw is the circular mean of the measured TCP x-axis headings in the world xy plane (the least-squares
heading on the unit circle). Everything else (robot base, TCP offset, block size, contact depth, home, joint
limits, counts, layout) is copied from the base calibration.

The fit's residual (measured minus fitted suction point) is reported for every point in mm, with each point's yaw
deviation from the mean and its tilt from vertical in deg; a warning names any point whose residual exceeds
:data:`RESIDUAL_WARN_MM` (probably mis-recorded: re-teach it or drop it). With the minimal workflow (one contact
pose per tower) the fit is exact and the residuals carry no information.

Refused inputs (one-line :class:`TaughtPointsError`, nothing written): missing or malformed file, unknown units,
a wrong joint count, radians given as degrees or vice versa, a pose outside the joint limits, a tower or height
outside the base calibration's grid, a tower with no taught point, a pose whose tool is tilted more than
:data:`MAX_TILT_DEG` from pointing down, and points that do not determine the grid.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
import yaml

from ur3hanoi import __version__
from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import CalibrationError, TaughtPointsError, printable
from ur3hanoi.grid import ABOVE, POSE_NAMES, T_world_tcp
from ur3hanoi.ik import wrap_angle
from ur3hanoi.io.atomic import atomic_write
from ur3hanoi.io.yaml_loader import parse_yaml
from ur3hanoi.robot import load_ur3
from ur3hanoi.station import Station, parse_station, station_to_dict
from ur3hanoi.taught import TaughtPoint, TaughtPoints

RESIDUAL_WARN_MM = 2.0  # [mm] a point farther than this from the fitted grid is probably mis-recorded
MAX_TILT_DEG = 10.0  # [deg] a taught pose's tool must point down within this (the table uses exactly down)
YAW_WARN_DEG = 2.0  # [deg] a heading this far from the mean suggests a mis-recorded wrist 3


def _fail(source: str, msg: str) -> TaughtPointsError:
    return TaughtPointsError(f"{printable(source)}: {msg}", source=source)


# ------------------------------------------------------------------------------------------------------ fitting


@dataclass(frozen=True)
class ResidualRow:
    """One row of the residual report (one taught point). Lengths [mm], angles [deg]."""

    index: int
    tower: int
    height: int
    pose: str
    residual_mm: float
    dx_mm: float
    dy_mm: float
    dz_mm: float
    yaw_dev_deg: float
    tilt_deg: float
    flagged: bool


@dataclass(frozen=True)
class CalibrationFit:
    """Result of :func:`fit_station`; everything a notebook needs to plot the fit.

    Attributes:
        station: the fitted station (base calibration with the new grid and tool yaw).
        points: the taught points, in input order.
        measured: FK suction points, shape (N, 3) [m, world].
        fitted: the fitted grid's suction points for the same slots, shape (N, 3) [m, world].
        residuals_mm: ``|measured - fitted|`` per point [mm], shape (N,).
        yaw_dev_deg: each point's TCP heading minus the fitted tool yaw [deg], shape (N,).
        tilt_deg: each point's tool tilt from pointing straight down [deg], shape (N,).
        fitted_params: which grid parameters the points determined (others come from the base calibration).
        dof: redundancy of the position fit (3 N minus the unknowns); 0 = exact fit.
        warnings: one line per suspicious point (residual over :data:`RESIDUAL_WARN_MM`, large yaw deviation).
    """

    station: Station
    points: tuple[TaughtPoint, ...]
    measured: FloatArray
    fitted: FloatArray
    residuals_mm: FloatArray
    yaw_dev_deg: FloatArray
    tilt_deg: FloatArray
    fitted_params: tuple[str, ...]
    dof: int
    warnings: tuple[str, ...]

    @property
    def rms_mm(self) -> float:
        """Root mean square of the residuals [mm]."""
        return float(np.sqrt(np.mean(self.residuals_mm**2)))

    @property
    def max_mm(self) -> float:
        return float(np.max(self.residuals_mm))

    def residual_table(self) -> list[ResidualRow]:
        """Per-point rows (``pandas.DataFrame(fit.residual_table())`` works)."""
        d = (self.measured - self.fitted) * 1e3
        return [
            ResidualRow(index=p.index, tower=p.tower, height=p.height, pose=POSE_NAMES[p.k],
                        residual_mm=float(self.residuals_mm[i]), dx_mm=float(d[i, 0]), dy_mm=float(d[i, 1]),
                        dz_mm=float(d[i, 2]), yaw_dev_deg=float(self.yaw_dev_deg[i]),
                        tilt_deg=float(self.tilt_deg[i]), flagged=bool(self.residuals_mm[i] > RESIDUAL_WARN_MM))
            for i, p in enumerate(self.points)
        ]


def _rot_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _default_height_step(base: Station, origins: FloatArray | None) -> FloatArray:
    """Height step [m, world] when the points do not determine it (see the module docstring).

    ``origins`` (T, 3) [m] are the fitted tower origins; None gives the base's step unrotated (flat layouts).
    """
    if base.layout == "stacked":
        return np.array([0.0, 0.0, base.block_size])
    if origins is None:
        return np.asarray(base.height_step, dtype=float)
    row_base = np.subtract(base.tower_origins[-1], base.tower_origins[0])
    row_fit = origins[-1] - origins[0]
    turn = math.atan2(row_fit[1], row_fit[0]) - math.atan2(row_base[1], row_base[0])
    return _rot_z(turn) @ np.asarray(base.height_step, dtype=float)


def _design(points: Sequence[TaughtPoint], n_towers: int, step_axes: Sequence[int], fit_approach: bool
            ) -> FloatArray:
    """Linear model matrix: 3 rows (x, y, z) per point; columns o_0..o_T-1, the fitted step axes, then a."""
    n_cols = 3 * n_towers + len(step_axes) + (1 if fit_approach else 0)
    A = np.zeros((3 * len(points), n_cols))
    for i, p in enumerate(points):
        rows = slice(3 * i, 3 * i + 3)
        A[rows, 3 * p.tower:3 * p.tower + 3] = np.eye(3)
        for c, axis in enumerate(step_axes):
            A[3 * i + axis, 3 * n_towers + c] = p.height
        if fit_approach and p.k == ABOVE:
            A[3 * i + 2, n_cols - 1] = 1.0
    return A


def _solve(A: FloatArray, b: FloatArray) -> FloatArray:
    x, *_ = np.linalg.lstsq(A, b, rcond=None)
    return np.asarray(x, dtype=float)


def fit_station(base: Station, taught: TaughtPoints | Sequence[TaughtPoint], name: str | None = None,
                source: str = "<memory>") -> CalibrationFit:
    """Fit the grid of ``base`` (tower origins, height step, approach, tool yaw) to taught poses.

    Args:
        base: calibration providing everything not fitted (robot base, tool offset, blocks, home, counts, layout).
        taught: the taught points (joint angles [rad]).
        name: name of the new station (default: the base's).
        source: recorded as the new station's ``source`` (the output file's path).

    Raises:
        TaughtPointsError: a point outside the grid or the joint limits, a tilted tool, a tower with no point,
            or points that do not determine the grid.
    """
    if isinstance(taught, TaughtPoints):
        points, where = taught.points, taught.source
    else:
        points, where = tuple(taught), "<memory>"
    if not points:
        raise _fail(where, "no taught points")

    robot = load_ur3(base.tool, base.limits)
    T_wb = base.T_world_base
    measured = np.empty((len(points), 3))
    headings = np.empty(len(points))
    tilts = np.empty(len(points))
    for i, p in enumerate(points):
        if not 0 <= p.tower < base.n_towers:
            raise _fail(where, f"{p.label}: tower {p.tower} is outside the base calibration's grid "
                               f"(towers 0..{base.n_towers - 1} in {base.source})")
        if not 0 <= p.height < base.n_heights:
            raise _fail(where, f"{p.label}: height {p.height} is outside the base calibration's grid "
                               f"(heights 0..{base.n_heights - 1} in {base.source})")
        q = np.asarray(p.q, dtype=float)
        if not base.limits.within_position(q):
            raise _fail(where, f"{p.label}: joint angles {np.round(np.degrees(q), 3).tolist()} deg are outside "
                               f"the joint limits of {base.source}")
        T = T_wb * robot.fk(q, "tcp")
        R = T.rotation
        measured[i] = T.translation
        tilts[i] = math.degrees(math.acos(min(1.0, max(-1.0, -float(R[2, 2])))))
        if tilts[i] > MAX_TILT_DEG:
            raise _fail(where, f"{p.label}: the tool is tilted {tilts[i]:.1f} deg from pointing down "
                               f"(at most {MAX_TILT_DEG:g} deg): not a pick pose, or a wrong tool offset in "
                               f"{base.source}")
        headings[i] = math.atan2(R[1, 0], R[0, 0])

    taught_towers = sorted({p.tower for p in points})
    missing = [t for t in range(base.n_towers) if t not in taught_towers]
    if missing:
        raise _fail(where, f"tower {missing[0]} has no taught point (towers taught: {taught_towers}; "
                           f"{base.source} has {base.n_towers} towers): teach at least its height-0 contact pose")

    # Tool yaw: circular mean, so headings either side of +-180 deg average correctly.
    yaw = math.atan2(float(np.mean(np.sin(headings))), float(np.mean(np.cos(headings))))
    yaw_dev = np.degrees(wrap_angle(headings - yaw))

    n_t = base.n_towers
    fit_approach = any(p.k == ABOVE for p in points)
    # A flat layout's height step is horizontal by definition: fit its x and y only.
    step_axes: tuple[int, ...] = (0, 1) if base.layout == "flat" else (0, 1, 2)
    b = measured.reshape(-1)
    A = _design(points, n_t, step_axes, fit_approach)
    fit_step = np.linalg.matrix_rank(A) == A.shape[1]
    if not fit_step:
        # The points do not determine the step (e.g. only height-0 poses): fix it and fit the rest.
        A = _design(points, n_t, (), fit_approach)
        if np.linalg.matrix_rank(A) < A.shape[1]:
            raise _fail(where, "the taught points do not determine the grid: teach a contact ('on') pose on "
                               "every tower, and above poses only on towers that also have a contact pose")
        # A flat layout's default step turns with the fitted tower row, which itself depends on the step through
        # any points above height 0: a few fixed-point passes settle it (one pass is exact for height-0 points).
        s = _default_height_step(base, None)
        for _ in range(3):
            x = _solve(A, b - np.concatenate([p.height * s for p in points]))
            s = _default_height_step(base, x[:3 * n_t].reshape(n_t, 3))
    else:
        x = _solve(A, b)
        s = np.zeros(3)
        s[list(step_axes)] = x[3 * n_t:3 * n_t + len(step_axes)]
    # Rounded to 1e-12 m (far below any physical meaning) so exact fits write 0.0 rather than -0.0 or 1e-17.
    origins = np.round(x[:3 * n_t].reshape(n_t, 3), 12) + 0.0
    s = np.round(s, 12) + 0.0
    approach = round(float(x[-1]), 12) if fit_approach else base.approach
    if not 0.0 < approach <= 0.5:
        raise _fail(where, f"the fitted approach height {approach:.4f} m is outside (0, 0.5] m: are some contact "
                           "poses marked 'pose: above' (or vice versa)?")

    try:
        station = base.with_grid(origins, s, yaw, approach, source=source)
    except CalibrationError as exc:
        # Re-raised as a taught-points error: the base file is fine, the fitted geometry is not.
        raise _fail(where, f"the fitted grid is invalid ({exc.allowed}; got {exc.field} = {exc.value}): "
                           "check the tower/height labels of the taught points") from None

    # The fitted grid's suction points, from the same grid model the tables are generated with.
    fitted = np.array([T_world_tcp(station, p.tower, p.height, p.k).translation for p in points])
    residuals_mm = np.linalg.norm(measured - fitted, axis=1) * 1e3
    warnings = []
    for i, p in enumerate(points):
        if residuals_mm[i] > RESIDUAL_WARN_MM:
            warnings.append(f"{p.label}: residual {residuals_mm[i]:.2f} mm > {RESIDUAL_WARN_MM:g} mm: "
                            "probably mis-recorded (re-teach or remove it)")
        if abs(yaw_dev[i]) > YAW_WARN_DEG:
            warnings.append(f"{p.label}: tool heading {yaw_dev[i]:+.2f} deg from the fitted yaw "
                            f"{math.degrees(yaw):.2f} deg (> {YAW_WARN_DEG:g} deg)")
    if name is not None:
        station = replace(station, name=name)
    params = ["tower_origins", "tool_yaw"]
    if fit_step:
        params.insert(1, "height_step")
    if fit_approach:
        params.append("approach")
    return CalibrationFit(
        station=station, points=points, measured=measured, fitted=fitted, residuals_mm=residuals_mm,
        yaw_dev_deg=yaw_dev, tilt_deg=tilts, fitted_params=tuple(params), dof=int(A.shape[0] - A.shape[1]),
        warnings=tuple(warnings),
    )


# ------------------------------------------------------------------------------------------------------ writing


def calibration_text(fit: CalibrationFit, taught: TaughtPoints, base: Station, taught_label: str | None = None,
                     base_label: str | None = None) -> str:
    """The output calibration file: a provenance header, then the station in calibration-file form.

    The bytes depend only on the inputs (no timestamps), so re-running gives an identical file.
    """
    body = yaml.safe_dump(station_to_dict(fit.station), sort_keys=False, default_flow_style=None, width=120)
    worst = int(np.argmax(fit.residuals_mm))
    head = [
        f"# Generated by ur3hanoi {__version__} calibrate: grid fitted to taught poses by least squares.",
        f"# taught: {printable(taught_label or taught.source, 4096)} (sha256 {taught.sha256 or 'n/a'})",
        f"# base:   {printable(base_label or base.source, 4096)} (sha256 {base.sha256 or 'n/a'})",
        f"# fitted: {', '.join(fit.fitted_params)}; {len(fit.points)} points, redundancy {fit.dof}, "
        f"residual rms {fit.rms_mm:.3f} mm, max {fit.max_mm:.3f} mm at {fit.points[worst].label}",
    ]
    return "\n".join(head) + "\n" + body


def write_calibration(path: str | Path, fit: CalibrationFit, taught: TaughtPoints, base: Station,
                      taught_label: str | None = None, base_label: str | None = None,
                      inputs: Sequence[str | Path] = ()) -> str:
    """Write the fitted station to ``path`` atomically after checking it loads back; returns the text.

    Raises:
        CalibrationError: the fitted station would not load back (e.g. an invalid name).
        OutputError: ``path`` cannot be written (one of ``inputs``, a directory, a device, no space...); nothing
            was written.
    """
    text = calibration_text(fit, taught, base, taught_label, base_label)
    # Never leave a file that `load_station` would reject.
    parse_station(parse_yaml(text, str(path), what="calibration file", error=CalibrationError), str(path))
    atomic_write(path, text, inputs=inputs)
    return text


__all__ = [
    "MAX_TILT_DEG",
    "RESIDUAL_WARN_MM",
    "YAW_WARN_DEG",
    "CalibrationFit",
    "ResidualRow",
    "calibration_text",
    "fit_station",
    "write_calibration",
]
