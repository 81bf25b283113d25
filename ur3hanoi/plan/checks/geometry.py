"""The robot's collision geometry for the clearance checks: the URDF's collision meshes as convex hulls.

Reading and hulling the meshes is most of a cold plan's clearance set-up (~0.1 s), and depends on nothing but the
robot model with its tool frame: :func:`robot_geometry` keeps the result in the user's cache
(:mod:`ur3hanoi.io.cache`), keyed by the URDF text, the collision meshes' bytes and the Pinocchio/coal versions.
The payload is Pinocchio's binary serialization (``GeometryModel.saveToBinary``), loaded only after its digest
matched, into a model equal to a fresh build (same objects, same distances).
"""

from __future__ import annotations

import contextlib
import os
import re
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING

from ur3hanoi.io import cache

if TYPE_CHECKING:
    import pinocchio as pin

    from ur3hanoi.robot.model import Ur3Model

COLLISION_GEOMETRY = "collision-geometry"
"""Kind of the user-cache entries of :func:`robot_geometry`."""

_MESH = re.compile(r'filename="([^"]+)"')
_COLLISION = re.compile(r"<collision\b.*?</collision>", re.S)


def build_robot_geometry(robot: Ur3Model) -> pin.GeometryModel:
    """The robot's URDF collision meshes, each replaced by its convex hull: ~30x faster GJK distances than the
    triangle BVHs, and a superset of each mesh, so a distance can only be under-estimated (the checks stay
    conservative)."""
    import coal
    import pinocchio as pin

    gm = pin.buildGeomFromUrdfString(robot.model, robot.urdf, pin.COLLISION)
    for g in gm.geometryObjects:
        if isinstance(g.geometry, coal.BVHModelBase):
            g.geometry.buildConvexRepresentation(False)
            g.geometry = g.geometry.convex
    return gm


def robot_geometry(robot: Ur3Model, build: Callable[[Ur3Model], pin.GeometryModel] | None = None
                   ) -> pin.GeometryModel:
    """``build(robot)`` (default :func:`build_robot_geometry`), from the user's cache when the same URDF text (with
    its tool frame), collision meshes and Pinocchio/coal versions built it before (loading is several times
    faster)."""
    import coal
    import pinocchio as pin

    make = build if build is not None else build_robot_geometry
    inputs = [f"pinocchio {pin.__version__}, coal {coal.__version__}".encode(), robot.urdf.encode()]
    for block in _COLLISION.findall(robot.urdf):
        for mesh in _MESH.findall(block):
            try:
                inputs.append(Path(mesh).read_bytes())
            except OSError:  # the build reports a missing mesh; cache nothing then
                return make(robot)
    key = cache.content_key(COLLISION_GEOMETRY, inputs)
    payload = cache.load(COLLISION_GEOMETRY, key)
    with _scratch_file() as path:
        if payload is None:
            gm = make(robot)
            gm.saveToBinary(str(path))
            cache.store(COLLISION_GEOMETRY, key, path.read_bytes())
            return gm
        path.write_bytes(payload)
        gm = pin.GeometryModel()
        try:
            gm.loadFromBinary(str(path))
        except RuntimeError:  # cannot happen for a digest-checked entry of these versions; rebuild all the same
            return make(robot)
        return gm


@contextlib.contextmanager
def _scratch_file() -> Iterator[Path]:
    """A private temporary file path (Pinocchio serializes to and from files only), removed afterwards."""
    import tempfile

    fd, name = tempfile.mkstemp(prefix="ur3hanoi-", suffix=".bin")
    os.close(fd)
    try:
        yield Path(name)
    finally:
        with contextlib.suppress(OSError):
            os.unlink(name)
