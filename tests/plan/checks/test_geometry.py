"""The robot's collision geometry for the clearance checks: convex hulls, kept in the user's cache and equal to a
fresh build when loaded from it."""

from __future__ import annotations

import base64
from pathlib import Path

import coal
import numpy as np
import pinocchio as pin
import pytest

from ur3hanoi.plan.checks.geometry import COLLISION_GEOMETRY, build_robot_geometry, robot_geometry
from ur3hanoi.robot.model import Ur3Model, load_ur3
from ur3hanoi.robot.urdf import ToolOffset
from ur3hanoi.station.calibration import Station


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "ur3hanoi"


def _corrupt_payload(path: Path) -> None:
    """One payload byte changed, still valid base64: the entry's digest catches it."""
    head, body = path.read_bytes().split(b"\n", 1)
    payload = bytearray(base64.b64decode(body))
    payload[1000] ^= 0x01
    path.write_bytes(head + b"\n" + base64.b64encode(bytes(payload)) + b"\n")


def _hulls(robot: Ur3Model, calls: list[int]) -> pin.GeometryModel:
    """:func:`build_robot_geometry`, counted."""
    calls.append(1)
    return build_robot_geometry(robot)


def _distances(robot: Ur3Model, gm: pin.GeometryModel) -> np.ndarray:
    """Distances [m] of every robot geometry to a few boxes at 20 seeded configurations."""
    gm = gm.copy()
    n = gm.ngeoms
    rng = np.random.default_rng(7)
    for i, p in enumerate(rng.uniform(-0.3, 0.3, size=(3, 3))):
        box_object = pin.GeometryObject(f"box{i}", 0, 0, pin.SE3(np.eye(3), p), coal.Box(0.03, 0.03, 0.03))
        box = gm.addGeometryObject(box_object)
        for g in range(n):
            gm.addCollisionPair(pin.CollisionPair(g, box))
    gd, data = pin.GeometryData(gm), robot.model.createData()
    out = []
    for q in rng.uniform(-np.pi, np.pi, size=(20, 6)):
        pin.updateGeometryPlacements(robot.model, data, gm, gd, q)
        out.append([pin.computeDistance(gm, gd, k).min_distance for k in range(len(gm.collisionPairs))])
    return np.array(out)


def test_collision_geometry_hit_equals_a_fresh_build(lab_sim: Station, private_cache: Path) -> None:
    robot = load_ur3(lab_sim.tool, lab_sim.limits)
    calls: list[int] = []
    fresh = robot_geometry(robot, lambda r: _hulls(r, calls))
    assert len(calls) == 1
    assert [p.name.split("-")[:2] for p in private_cache.iterdir()] == [["collision", "geometry"]]
    cached = robot_geometry(robot, lambda r: _hulls(r, calls))
    assert len(calls) == 1  # loaded, not built
    assert [g.name for g in cached.geometryObjects] == [g.name for g in fresh.geometryObjects]
    assert [g.parentJoint for g in cached.geometryObjects] == [g.parentJoint for g in fresh.geometryObjects]
    d_fresh, d_cached = _distances(robot, fresh), _distances(robot, cached)
    assert d_fresh.min() > -1.0 and np.isfinite(d_fresh).all()
    np.testing.assert_array_equal(d_cached, d_fresh)  # bit for bit: the same hulls


def test_collision_geometry_key_follows_the_robot_model(lab_sim: Station, private_cache: Path) -> None:
    """Another tool frame is another URDF text: a new entry (the first is kept); the same one is a hit."""
    calls: list[int] = []
    robot = load_ur3(lab_sim.tool, lab_sim.limits)
    other = Ur3Model(ToolOffset(parent="tool0", xyz=(0.0, 0.0, 0.1)), lab_sim.limits)
    for r in (robot, other, robot, other):
        robot_geometry(r, lambda r: _hulls(r, calls))
    assert len(calls) == 2
    assert len(list(private_cache.glob(f"{COLLISION_GEOMETRY}-*.cache"))) == 2


def test_corrupt_collision_entry_is_rebuilt(lab_sim: Station, private_cache: Path) -> None:
    robot = load_ur3(lab_sim.tool, lab_sim.limits)
    calls: list[int] = []
    fresh = robot_geometry(robot, lambda r: _hulls(r, calls))
    (entry,) = private_cache.glob("*.cache")
    _corrupt_payload(entry)
    rebuilt = robot_geometry(robot, lambda r: _hulls(r, calls))
    assert len(calls) == 2
    np.testing.assert_array_equal(_distances(robot, rebuilt), _distances(robot, fresh))
    robot_geometry(robot, lambda r: _hulls(r, calls))
    assert len(calls) == 2  # the rebuilt entry is whole again
