"""Station calibration: a YAML file describing one lab station, loaded into frozen dataclasses.

A station is the robot's base pose in the world, the suction tool offset, the block size and the tower grid.
Every pose is in the **world** frame of the station (z up, table surface horizontal) unless its name says
otherwise. See ``ur3hanoi/stations/README.md`` for the file reference.

Example (the course's flat Gazebo layout)::

    name: lab_sim
    layout: flat                       # flat | stacked
    robot:
      base_xyz: [-0.15, 0.15, 0.01]    # controller `base` (DH) frame origin in world [m]
      base_rpy_deg: [0, 0, 0]          # its orientation in world (URDF rpy) [deg]
      home_deg: [120, -90, 90, -90, -90, 0]
      elbow_limit_deg: 360             # optional; ROS configs often use 180
    tool:
      parent: ee_link                  # ee_link | tool0
      xyz: [0.059, 0.0535, 0.0]        # suction point in the parent frame [m]
      rpy_deg: [0, 90, 0]              # suction frame in the parent frame [deg]
      yaw_deg: 90                      # direction of the TCP x axis in the world xy plane [deg]
    blocks:
      size: 0.0318                     # cube edge [m]
      contact_depth: 0.0193            # suction point below the block's top face at contact [m]
    grid:
      towers: 3
      heights: 3
      origin: [0.40, 0.05, 0.0125]     # contact suction point, tower 0 / height 0, world [m]
      tower_step: [0.0, 0.10, 0.0]     # or `tower_origins: [[x, y, z], ...]` (one per tower)
      height_step: [-0.10, 0.0, 0.0]   # flat: horizontal; stacked: [0, 0, block size]
      approach: 0.096                  # "above" pose = "on" pose + approach along world +z [m]
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pinocchio as pin
import yaml

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import CalibrationError
from ur3hanoi.resources import station_file, station_names
from ur3hanoi.robot import FLANGE_FRAMES, N_JOINTS, JointLimits, ToolOffset

Vec3 = tuple[float, float, float]
Layout = Literal["flat", "stacked"]
LAYOUTS: tuple[str, ...] = ("flat", "stacked")

MAX_TOWERS = 10
MAX_HEIGHTS = 20


@dataclass(frozen=True)
class Station:
    """One calibrated lab station. Lengths [m], angles [rad], poses in the station's world frame.

    Attributes:
        name: station name (free text).
        layout: ``"flat"`` (blocks side by side on the table, like the course's Gazebo world) or ``"stacked"``.
        base_xyz, base_rpy: the controller ``base`` (DH) frame in world.
        q_home: home joint configuration [rad], controller convention.
        limits: joint limits (datasheet, with the configured elbow limit).
        tool: suction point (TCP) offset from a flange frame.
        tool_yaw: direction of the TCP x axis in the world xy plane [rad]; the TCP z axis points down.
        block_size: cube edge [m].
        contact_depth: suction point below the block's top face at contact [m].
        tower_origins: contact suction point of each tower at height 0, world [m].
        height_step: world displacement [m] of the contact point from one height to the next.
        n_heights: number of heights (rows or levels) per tower.
        approach: "above" pose = "on" pose + approach * world z [m].
        source: file the station was read from ("<memory>" if built in code).
        sha256: hex digest of that file's bytes ("" if built in code).
    """

    name: str
    layout: Layout
    base_xyz: Vec3
    base_rpy: Vec3
    q_home: tuple[float, ...]
    limits: JointLimits
    tool: ToolOffset
    tool_yaw: float
    block_size: float
    contact_depth: float
    tower_origins: tuple[Vec3, ...]
    height_step: Vec3
    n_heights: int
    approach: float
    source: str = "<memory>"
    sha256: str = ""

    @property
    def n_towers(self) -> int:
        return len(self.tower_origins)

    @property
    def T_world_base(self) -> pin.SE3:
        """Pose of the controller ``base`` frame in world."""
        return pin.SE3(pin.rpy.rpyToMatrix(*self.base_rpy), np.array(self.base_xyz, dtype=float))

    @property
    def q_home_array(self) -> FloatArray:
        return np.array(self.q_home, dtype=float)

    def with_grid(
        self,
        tower_origins: Sequence[Sequence[float]],
        height_step: Sequence[float],
        tool_yaw: float,
        approach: float | None = None,
        source: str = "<memory>",
    ) -> Station:
        """A copy with a new grid (used by calibration); validated like a loaded file."""
        new = replace(
            self,
            tower_origins=tuple(_vec3(p) for p in tower_origins),
            height_step=_vec3(height_step),
            tool_yaw=float(tool_yaw),
            approach=self.approach if approach is None else float(approach),
            source=source,
            sha256="",
        )
        validate(new)
        return new


def _vec3(v: Sequence[float]) -> Vec3:
    a = [float(x) for x in v]
    return (a[0], a[1], a[2])


# ---------------------------------------------------------------------------------------------- parsing helpers


class _Reader:
    """Reads typed fields from the parsed YAML, raising CalibrationError that names file and field."""

    def __init__(self, source: str, data: Mapping[str, Any]) -> None:
        self.source = source
        self.data = data

    def fail(self, field: str, value: object, allowed: str) -> CalibrationError:
        return CalibrationError(self.source, field, value, allowed)

    def get(self, path: str, required: bool = True, default: Any = None) -> Any:
        node: Any = self.data
        for part in path.split("."):
            if not isinstance(node, Mapping) or part not in node:
                if required:
                    raise self.fail(path, "<missing>", "a value (the field is required)")
                return default
            node = node[part]
        return node

    def number(self, path: str, value: Any, lo: float = -math.inf, hi: float = math.inf,
               lo_open: bool = False, what: str = "a number") -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(path, value, what)
        x = float(value)
        if not math.isfinite(x):
            raise self.fail(path, value, f"a finite {what}")
        if x < lo or x > hi or (lo_open and x == lo):
            lo_s = "(" if lo_open else "["
            raise self.fail(path, value, f"{what} in {lo_s}{lo}, {hi}]")
        return x

    def vector(self, path: str, n: int, value: Any = None, unit: str = "", lo: float = -math.inf,
               hi: float = math.inf) -> tuple[float, ...]:
        value = self.get(path) if value is None else value
        if not isinstance(value, list | tuple) or len(value) != n:
            raise self.fail(path, value, f"a list of {n} numbers{unit}")
        return tuple(self.number(f"{path}[{i}]", v, lo, hi, what=f"a number{unit}") for i, v in enumerate(value))

    def integer(self, path: str, lo: int, hi: int) -> int:
        value = self.get(path)
        if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
            raise self.fail(path, value, f"an integer in [{lo}, {hi}]")
        return int(value)

    def angles(self, base: str, n: int, required: bool = True, lo_deg: float = -math.inf,
               hi_deg: float = math.inf) -> tuple[float, ...] | None:
        """Reads ``<base>_deg`` or ``<base>_rad`` (exactly one) and returns radians."""
        deg, rad = f"{base}_deg", f"{base}_rad"
        has_deg = self.get(deg, required=False) is not None
        has_rad = self.get(rad, required=False) is not None
        if has_deg and has_rad:
            raise self.fail(rad, self.get(rad), f"absent when '{deg}' is given (give one of them)")
        if not has_deg and not has_rad:
            if required:
                raise self.fail(deg, "<missing>", f"a list of {n} angles [deg] (or '{rad}' [rad])")
            return None
        if has_deg:
            vals = self.vector(deg, n, unit=" [deg]", lo=lo_deg, hi=hi_deg)
            return tuple(math.radians(v) for v in vals)
        return self.vector(rad, n, unit=" [rad]", lo=math.radians(lo_deg), hi=math.radians(hi_deg))


def load_station(path: str | Path) -> Station:
    """Read and validate a station calibration file, or a shipped station by name (``lab_sim``, ``lab_real``).

    Raises:
        CalibrationError: the file is missing or unreadable, or a field is missing or out of range; the message
            names the file, the field, the bad value and what is allowed.
    """
    p = station_file(path)
    source = str(path)
    try:
        raw = p.read_bytes()
    except OSError as exc:
        names = ", ".join(station_names())
        raise CalibrationError(source, "<file>", str(p), f"a readable calibration file ({exc.strerror}) or a "
                               f"shipped station name ({names})") from None
    try:
        data = yaml.safe_load(raw)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f"line {mark.line + 1}" if mark is not None else "?"
        raise CalibrationError(source, "<file>", where, "valid YAML") from None
    if not isinstance(data, Mapping):
        raise CalibrationError(source, "<file>", type(data).__name__, "a YAML mapping of calibration fields")
    station = parse_station(data, source)
    return replace(station, sha256=hashlib.sha256(raw).hexdigest())


def parse_station(data: Mapping[str, Any], source: str = "<memory>") -> Station:
    """Build a :class:`Station` from parsed YAML (see the module docstring for the fields)."""
    r = _Reader(source, data)
    name = r.get("name", required=False, default=Path(source).stem)
    if not isinstance(name, str) or not name:
        raise r.fail("name", name, "a non-empty string")
    layout = r.get("layout")
    if layout not in LAYOUTS:
        raise r.fail("layout", layout, f"one of {LAYOUTS}")

    base_xyz = r.vector("robot.base_xyz", 3, unit=" [m]")
    base_rpy = r.angles("robot.base_rpy", 3, required=False) or (0.0, 0.0, 0.0)
    elbow_deg = r.get("robot.elbow_limit_deg", required=False, default=360.0)
    elbow = math.radians(r.number("robot.elbow_limit_deg", elbow_deg, 0.0, 360.0, lo_open=True))
    limits = JointLimits.ur3(elbow_limit=elbow)
    q_home = r.angles("robot.home", N_JOINTS)
    assert q_home is not None

    parent = r.get("tool.parent")
    if parent not in FLANGE_FRAMES:
        raise r.fail("tool.parent", parent, f"one of {FLANGE_FRAMES}")
    tool_xyz = r.vector("tool.xyz", 3, unit=" [m]", lo=-0.5, hi=0.5)
    tool_rpy = r.angles("tool.rpy", 3)
    assert tool_rpy is not None
    tool = ToolOffset(parent=parent, xyz=_vec3(tool_xyz), rpy=_vec3(tool_rpy))
    yaw_deg = r.get("tool.yaw_deg")
    tool_yaw = math.radians(r.number("tool.yaw_deg", yaw_deg, -360.0, 360.0, what="an angle [deg]"))

    block_size = r.number("blocks.size", r.get("blocks.size"), 0.0, 0.2, lo_open=True, what="a length [m]")
    depth = r.number("blocks.contact_depth", r.get("blocks.contact_depth"), 0.0, block_size,
                     what="a length [m] (at most blocks.size)")

    n_towers = r.integer("grid.towers", 2, MAX_TOWERS)
    n_heights = r.integer("grid.heights", 1, MAX_HEIGHTS)
    explicit = r.get("grid.tower_origins", required=False)
    if explicit is not None:
        for key in ("grid.origin", "grid.tower_step"):
            if r.get(key, required=False) is not None:
                raise r.fail(key, r.get(key), "absent when 'grid.tower_origins' is given (give one form)")
        if not isinstance(explicit, list) or len(explicit) != n_towers:
            raise r.fail("grid.tower_origins", explicit, f"a list of grid.towers = {n_towers} points [x, y, z]")
        origins = tuple(
            _vec3(r.vector(f"grid.tower_origins[{i}]", 3, value=p, unit=" [m]")) for i, p in enumerate(explicit)
        )
    else:
        origin = np.array(r.vector("grid.origin", 3, unit=" [m]"))
        step = np.array(r.vector("grid.tower_step", 3, unit=" [m]"))
        origins = tuple(_vec3(origin + t * step) for t in range(n_towers))
    height_step = _vec3(r.vector("grid.height_step", 3, unit=" [m]"))
    approach = r.number("grid.approach", r.get("grid.approach"), 0.0, 0.5, lo_open=True, what="a length [m]")

    station = Station(
        name=name, layout=layout, base_xyz=_vec3(base_xyz), base_rpy=_vec3(base_rpy), q_home=tuple(q_home),
        limits=limits, tool=tool, tool_yaw=tool_yaw, block_size=block_size, contact_depth=depth,
        tower_origins=origins, height_step=height_step, n_heights=n_heights, approach=approach, source=source,
    )
    validate(station)
    return station


def validate(s: Station) -> None:
    """Cross-field checks: limits, grid geometry per layout, block overlaps. Raises CalibrationError."""
    src = s.source
    if not s.limits.within_position(s.q_home_array):
        raise CalibrationError(src, "robot.home_deg", [round(math.degrees(v), 6) for v in s.q_home],
                               "joint angles within the UR3 limits (+-360 deg; elbow within robot.elbow_limit_deg)")
    step = np.array(s.height_step)
    horiz, vert = float(np.linalg.norm(step[:2])), float(step[2])
    if s.n_heights > 1 or np.linalg.norm(step) > 0:
        if s.layout == "flat":
            if abs(vert) > 1e-6 or horiz < s.block_size:
                raise CalibrationError(src, "grid.height_step", list(s.height_step),
                                       f"a horizontal vector (z = 0) at least blocks.size = {s.block_size} m long "
                                       "for layout 'flat'")
        elif not (0.9 * s.block_size <= vert <= 1.1 * s.block_size and horiz <= 0.25 * s.block_size):
            raise CalibrationError(src, "grid.height_step", list(s.height_step),
                                   f"a vertical vector of about one block ({s.block_size} m, +-10%) "
                                   "for layout 'stacked'")
    # Towers must not overlap: their height-0 slots at least one block apart in the table plane.
    for i, a in enumerate(s.tower_origins):
        for j in range(i + 1, s.n_towers):
            b = s.tower_origins[j]
            if np.linalg.norm(np.subtract(a, b)[:2]) < s.block_size:
                raise CalibrationError(src, "grid.tower_origins", [list(a), list(b)],
                                       f"towers {i} and {j} at least blocks.size = {s.block_size} m apart in xy")


def station_to_dict(s: Station) -> dict[str, Any]:
    """The calibration-file form of a station (explicit tower origins, angles in degrees)."""

    def deg(v: Sequence[float]) -> list[float]:
        return [round(math.degrees(x), 12) for x in v]

    def rnd(v: Sequence[float]) -> list[float]:
        return [round(float(x), 12) for x in v]

    return {
        "name": s.name,
        "layout": s.layout,
        "robot": {
            "base_xyz": rnd(s.base_xyz),
            "base_rpy_deg": deg(s.base_rpy),
            "home_deg": deg(s.q_home),
            "elbow_limit_deg": round(math.degrees(s.limits.q_max[2]), 12),
        },
        "tool": {
            "parent": s.tool.parent,
            "xyz": rnd(s.tool.xyz),
            "rpy_deg": deg(s.tool.rpy),
            "yaw_deg": round(math.degrees(s.tool_yaw), 12),
        },
        "blocks": {"size": s.block_size, "contact_depth": s.contact_depth},
        "grid": {
            "towers": s.n_towers,
            "heights": s.n_heights,
            "tower_origins": [rnd(o) for o in s.tower_origins],
            "height_step": rnd(s.height_step),
            "approach": round(s.approach, 12),
        },
    }
