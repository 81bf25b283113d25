"""Station calibration: a YAML file describing one lab station, loaded into frozen dataclasses.

A station is the robot's base pose in the world, the suction tool offset, the block size and the tower grid.
Every pose is in the **world** frame of the station (z up, table surface horizontal) unless its name says
otherwise. See ``ur3hanoi/station/shipped/README.md`` for the file reference.

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

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal

import numpy as np

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import MISSING, CalibrationError, printable
from ur3hanoi.io.limits import MAX_HEIGHTS, MAX_TOWERS
from ur3hanoi.io.resources import station_file, station_names
from ur3hanoi.io.schema import Choice, Field, ListOf, Number, Record, Text, Vector
from ur3hanoi.io.schema import validate as validate_schema
from ur3hanoi.io.yaml_loader import load_yaml_file
from ur3hanoi.robot.chain import rpy_matrix
from ur3hanoi.robot.model import JointLimits
from ur3hanoi.robot.registry import DEFAULT_ROBOT, N_JOINTS, ROBOTS, RobotDescription
from ur3hanoi.robot.urdf import FLANGE_FRAMES, ToolOffset
from ur3hanoi.station.suction_profile import (
    DEFAULT_PROFILE,
    PROFILES,
    SUCTION_SECTION,
    SuctionProfile,
    parse_suction,
    suction_section,
)
from ur3hanoi.station.suction_wiring import IO_SECTION, SuctionWiring, course_wiring, parse_wiring

if TYPE_CHECKING:
    import pinocchio as pin

Vec3 = tuple[float, float, float]
DEFAULT_WIRING = course_wiring(DEFAULT_ROBOT)
Layout = Literal["flat", "stacked"]
LAYOUTS: tuple[str, ...] = ("flat", "stacked")


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
        suction: what the suction feedback reads (``suction:`` section; the course simulator's levels by
            default), see :mod:`ur3hanoi.station.suction_profile`.
        robot: the arm (``robot.model``; the UR3 by default), see :mod:`ur3hanoi.robot.registry`.
        wiring: the suction's pins for the official UR drivers (``io:`` section; the course's wiring on the arm by
            default), see :mod:`ur3hanoi.station.suction_wiring`.
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
    suction: SuctionProfile = DEFAULT_PROFILE
    robot: RobotDescription = DEFAULT_ROBOT
    wiring: SuctionWiring = DEFAULT_WIRING

    @property
    def n_towers(self) -> int:
        return len(self.tower_origins)

    @property
    def T_world_base(self) -> pin.SE3:
        """Pose of the controller ``base`` frame in world."""
        import pinocchio as pin

        return pin.SE3(pin.rpy.rpyToMatrix(*self.base_rpy), np.array(self.base_xyz, dtype=float))

    @property
    def H_world_base(self) -> FloatArray:
        """:attr:`T_world_base` as a 4x4 matrix (NumPy only, the same bits)."""
        H = np.eye(4)
        H[:3, :3] = rpy_matrix(*self.base_rpy)
        H[:3, 3] = self.base_xyz
        return H

    @property
    def q_home_array(self) -> FloatArray:
        return np.array(self.q_home, dtype=float)

    def with_grid(
        self,
        tower_origins: Sequence[Sequence[float]] | FloatArray,
        height_step: Sequence[float] | FloatArray,
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


def _vec3(v: Sequence[float] | FloatArray) -> Vec3:
    a = [float(x) for x in v]
    return (a[0], a[1], a[2])


# ------------------------------------------------------------------------------------------------------ schema

_M = "m"
_LENGTH = Number(-10.0, 10.0, unit=_M, what="a length")
_POINT = Vector(3, _LENGTH)
_DEG = Number(-360.0, 360.0, unit="deg", what="an angle")
_RAD = Number(-2 * math.pi, 2 * math.pi, unit="rad", what="an angle")


def _angles(prefix: str, n: int) -> dict[str, Field]:
    """The ``<prefix>_deg`` / ``<prefix>_rad`` pair (exactly one of them is given; checked by the parser)."""
    return {f"{prefix}_deg": Field(Vector(n, _DEG), required=False),
            f"{prefix}_rad": Field(Vector(n, _RAD), required=False)}


STATION_SCHEMA = Record({
    "name": Field(Text(max_len=255), required=False),
    "layout": Field(Choice(LAYOUTS)),
    "robot": Field(Record({
        "model": Field(Choice(tuple(ROBOTS)), required=False),
        "base_xyz": Field(_POINT),
        **_angles("base_rpy", 3),
        **_angles("home", N_JOINTS),
        "elbow_limit_deg": Field(Number(0.0, 360.0, lo_open=True, unit="deg", what="an angle"), required=False),
    })),
    "tool": Field(Record({
        "parent": Field(Choice(FLANGE_FRAMES)),
        "xyz": Field(Vector(3, Number(-0.5, 0.5, unit=_M, what="a length"))),
        **_angles("rpy", 3),
        "yaw_deg": Field(_DEG),
    })),
    "blocks": Field(Record({
        "size": Field(Number(0.0, 0.2, lo_open=True, unit=_M, what="a length")),
        "contact_depth": Field(Number(0.0, 0.2, unit=_M, what="a length")),
    })),
    "grid": Field(Record({
        "towers": Field(Number(2, MAX_TOWERS, integer=True)),
        "heights": Field(Number(1, MAX_HEIGHTS, integer=True)),
        "origin": Field(_POINT, required=False),
        "tower_step": Field(_POINT, required=False),
        "tower_origins": Field(ListOf(_POINT, 2, MAX_TOWERS, what="points [x, y, z]"), required=False),
        "height_step": Field(_POINT),
        "approach": Field(Number(0.0, 0.5, lo_open=True, unit=_M, what="a length")),
    })),
    "suction": Field(SUCTION_SECTION, required=False),
    "io": Field(IO_SECTION, required=False),
})
"""The calibration file's schema: every key, its type and range (see ``ur3hanoi/station/shipped/README.md``)."""


def _angles_rad(source: str, section: Mapping[str, Any], path: str, prefix: str, n: int,
                default: tuple[float, ...] | None = None) -> tuple[float, ...]:
    """Radians from ``<prefix>_deg`` or ``<prefix>_rad`` (exactly one, or neither when there is a default)."""
    deg, rad = section.get(f"{prefix}_deg"), section.get(f"{prefix}_rad")
    if deg is not None and rad is not None:
        raise CalibrationError.invalid(source, f"{path}.{prefix}_rad", rad,
                                       f"absent when '{path}.{prefix}_deg' is given (give one of them)")
    if deg is not None:
        return tuple(math.radians(float(v)) for v in deg)
    if rad is not None:
        return tuple(float(v) for v in rad)
    if default is None:
        raise CalibrationError.invalid(source, f"{path}.{prefix}_deg", MISSING,
                                       f"a list of {n} angles [deg] (or '{path}.{prefix}_rad' [rad])")
    return default


def load_station(path: str | Path) -> Station:
    """Read and validate a station calibration file, or a shipped station by name (``lab_sim``, ``lab_real``).

    The file is read and parsed by the strict loader (:mod:`ur3hanoi.io.yaml_loader`) and checked against
    :data:`STATION_SCHEMA`.

    Raises:
        CalibrationError: the file is missing, unreadable, not strict YAML, has an unknown, missing or duplicate
            key, or a value of the wrong type or out of range; the message names the file, the field, the bad
            value and what is allowed.
    """
    source = str(path)
    doc = load_yaml_file(station_file(path), what="calibration file", error=CalibrationError, source=source,
                         missing_hint=f"; shipped stations: {', '.join(station_names())}")
    station = parse_station(doc.data, source)
    return replace(station, sha256=doc.sha256)


def parse_station(data: Any, source: str = "<memory>") -> Station:
    """Build a :class:`Station` from a parsed calibration document (see the module docstring for the fields).

    Raises:
        CalibrationError: the document does not match :data:`STATION_SCHEMA` or fails a cross-field check.
    """
    validate_schema(data, STATION_SCHEMA, source, CalibrationError)
    robot, tool, blocks, grid = data["robot"], data["tool"], data["blocks"], data["grid"]
    name = data.get("name", printable(Path(source).stem, 255))
    layout = data["layout"]

    base_rpy = _angles_rad(source, robot, "robot", "base_rpy", 3, default=(0.0, 0.0, 0.0))
    elbow = math.radians(float(robot.get("elbow_limit_deg", 360.0)))
    arm = ROBOTS[robot.get("model", DEFAULT_ROBOT.name)]
    limits = JointLimits.for_robot(arm, elbow_limit=elbow)
    q_home = _angles_rad(source, robot, "robot", "home", N_JOINTS)
    tool_rpy = _angles_rad(source, tool, "tool", "rpy", 3)
    tool_offset = ToolOffset(parent=tool["parent"], xyz=_vec3(tool["xyz"]), rpy=_vec3(tool_rpy))
    tool_yaw = math.radians(float(tool["yaw_deg"]))

    block_size = float(blocks["size"])
    depth = float(blocks["contact_depth"])
    if depth > block_size:
        raise CalibrationError.invalid(source, "blocks.contact_depth", blocks["contact_depth"],
                                       f"a length [m] in [0, {block_size:g}] (at most blocks.size)")

    n_towers, n_heights = int(grid["towers"]), int(grid["heights"])
    explicit = grid.get("tower_origins")
    if explicit is not None:
        for key in ("origin", "tower_step"):
            if key in grid:
                raise CalibrationError.invalid(source, f"grid.{key}", grid[key],
                                               "absent when 'grid.tower_origins' is given (give one form)")
        if len(explicit) != n_towers:
            raise CalibrationError.invalid(source, "grid.tower_origins", explicit,
                                           f"a list of grid.towers = {n_towers} points [x, y, z]")
        origins = tuple(_vec3(p) for p in explicit)
    else:
        for key in ("origin", "tower_step"):
            if key not in grid:
                raise CalibrationError.invalid(source, f"grid.{key}", MISSING,
                                               "a list of 3 numbers [m] (or 'grid.tower_origins' instead of "
                                               "'grid.origin' and 'grid.tower_step')")
        origin = np.array(grid["origin"], dtype=float)
        step = np.array(grid["tower_step"], dtype=float)
        origins = tuple(_vec3(origin + t * step) for t in range(n_towers))

    suction = parse_suction(data.get("suction"))
    station = Station(
        name=name, layout=layout, base_xyz=_vec3(robot["base_xyz"]), base_rpy=_vec3(base_rpy), q_home=q_home,
        limits=limits, tool=tool_offset, tool_yaw=tool_yaw, block_size=block_size, contact_depth=depth,
        tower_origins=origins, height_step=_vec3(grid["height_step"]), n_heights=n_heights,
        approach=float(grid["approach"]), source=source, suction=suction, robot=arm,
        wiring=parse_wiring(data.get("io"), arm, source),
    )
    validate(station)
    return station


def with_suction_profile(station: Station, name: str) -> Station:
    """``station`` with the named suction profile (``lab_sim``, ``real``) instead of its calibration's.

    Raises:
        CalibrationError: ``name`` is not a profile.
    """
    if name not in PROFILES:
        raise CalibrationError(f"suction profile {printable(name, 60)!r} is unknown: expected one of "
                               f"{', '.join(PROFILES)}")
    return replace(station, suction=PROFILES[name])


def validate(s: Station) -> None:
    """Cross-field checks: limits, grid geometry per layout, block overlaps. Raises CalibrationError."""
    fail = CalibrationError.invalid
    src = s.source
    if not s.limits.within_position(s.q_home_array):
        raise fail(src, "robot.home_deg", [round(math.degrees(v), 6) for v in s.q_home],
                   f"joint angles within the {s.robot.name.upper()} limits (+-360 deg; elbow within "
                   "robot.elbow_limit_deg)")
    step = np.array(s.height_step)
    horiz, vert = float(np.linalg.norm(step[:2])), float(step[2])
    if s.n_heights > 1 or np.linalg.norm(step) > 0:
        if s.layout == "flat":
            if abs(vert) > 1e-6 or horiz < s.block_size:
                raise fail(src, "grid.height_step", list(s.height_step),
                           f"a horizontal vector (z = 0) at least blocks.size = {s.block_size} m long for layout "
                           "'flat'")
        elif not (0.9 * s.block_size <= vert <= 1.1 * s.block_size and horiz <= 0.25 * s.block_size):
            raise fail(src, "grid.height_step", list(s.height_step),
                       f"a vertical vector of about one block ({s.block_size} m, +-10%) for layout 'stacked'")
    # Towers must not overlap: their height-0 slots at least one block apart in the table plane.
    for i, a in enumerate(s.tower_origins):
        for j in range(i + 1, s.n_towers):
            b = s.tower_origins[j]
            if np.linalg.norm(np.subtract(a, b)[:2]) < s.block_size:
                raise fail(src, "grid.tower_origins", [list(a), list(b)],
                           f"towers {i + 1} and {j + 1} at least blocks.size = {s.block_size} m apart in xy")


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
            **({} if s.robot == DEFAULT_ROBOT else {"model": s.robot.name}),
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
        "suction": suction_section(s.suction),
        **({} if s.wiring == course_wiring(s.robot) else {"io": s.wiring.as_dict()}),
    }
