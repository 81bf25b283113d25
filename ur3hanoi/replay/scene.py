"""The replay's 3-D scene as meshcat viewer commands: every drawn MuJoCo geom (the UR3's meshes as compiled by
MuJoCo, the blocks in their colours, the table), a pad under every slot of the towers, the camera, and one
animation clip per moving geom (position and quaternion keyframes, in seconds of sim time).

The commands are meshcat's own (``meshcat.commands``, ``meshcat.geometry``, packed with ``umsgpack`` as meshcat
sends them), replayed by meshcat's three.js viewer in the page (:mod:`ur3hanoi.replay.page`).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterator
from typing import Any

import mujoco
import numpy as np
import umsgpack
from meshcat import geometry as mg
from meshcat.commands import SetObject, SetProperty, SetTransform
from meshcat.path import Path as McPath

from ur3hanoi.arrays import FloatArray
from ur3hanoi.replay.recorder import PoseTrack
from ur3hanoi.sim.scene import slot_centers
from ur3hanoi.station.calibration import Station

ROOT = McPath(("meshcat", "ur3hanoi"))
"""Where the replay's objects live in meshcat's scene tree."""

POSE_TOLERANCE = 1e-7
"""A keyframe equal to both neighbours within this [m, or quaternion component] is left out (linear/slerp
interpolation redraws it exactly): a block at rest costs two keyframes, not one per frame."""

Command = dict[str, Any]

_UUIDS = itertools.count()


class IndexedMesh(mg.Geometry):
    """A triangle mesh with per-vertex normals (meshcat's ``TriangularMeshGeometry`` has none: three.js would
    smooth every edge)."""

    def __init__(self, vertices: FloatArray, normals: FloatArray, faces: np.ndarray) -> None:
        super().__init__()
        self.vertices = np.asarray(vertices, dtype=np.float32)
        self.normals = np.asarray(normals, dtype=np.float32)
        self.faces = np.asarray(faces, dtype=np.uint32)

    def lower(self, object_data: Any) -> dict[str, Any]:
        return {"uuid": self.uuid, "type": "BufferGeometry",
                "data": {"attributes": {"position": mg.pack_numpy_array(self.vertices.T),
                                        "normal": mg.pack_numpy_array(self.normals.T)},
                         "index": mg.pack_numpy_array(self.faces.T)}}


def _mesh_geometry(model: mujoco.MjModel, mesh: int) -> IndexedMesh:
    """MuJoCo's compiled mesh in its geom's frame, split so that every corner carries its face's normal index."""
    v0, nv = model.mesh_vertadr[mesh], model.mesh_vertnum[mesh]
    f0, nf = model.mesh_faceadr[mesh], model.mesh_facenum[mesh]
    n0 = model.mesh_normaladr[mesh]
    verts = model.mesh_vert[v0:v0 + nv]
    faces = model.mesh_face[f0:f0 + nf]
    fnorm = model.mesh_facenormal[f0:f0 + nf]
    normals = model.mesh_normal[n0:n0 + model.mesh_normalnum[mesh]]
    # Unique (vertex, normal) corners.
    corners = np.stack([faces.reshape(-1), fnorm.reshape(-1)], axis=1)
    uniq, inverse = np.unique(corners, axis=0, return_inverse=True)
    return IndexedMesh(verts[uniq[:, 0]], normals[uniq[:, 1]], inverse.reshape(-1, 3))


def _hex(rgba: np.ndarray) -> int:
    r, g, b = (round(255 * float(np.clip(c, 0.0, 1.0))) for c in rgba[:3])
    return (r << 16) | (g << 8) | b


def _rx90() -> FloatArray:
    """three.js cylinders run along y; MuJoCo's along z."""
    T = np.eye(4)
    T[1:3, 1:3] = [[0.0, -1.0], [1.0, 0.0]]
    return T


def _shapes(model: mujoco.MjModel, g: int) -> list[tuple[mg.Geometry, FloatArray]]:
    """meshcat geometries (with their pose in the geom frame) that draw geom ``g``."""
    kind, size = model.geom_type[g], model.geom_size[g]
    if kind == mujoco.mjtGeom.mjGEOM_MESH:
        return [(_mesh_geometry(model, int(model.geom_dataid[g])), np.eye(4))]
    if kind == mujoco.mjtGeom.mjGEOM_BOX:
        return [(mg.Box(list(2.0 * size)), np.eye(4))]
    if kind == mujoco.mjtGeom.mjGEOM_SPHERE:
        return [(mg.Sphere(float(size[0])), np.eye(4))]
    if kind == mujoco.mjtGeom.mjGEOM_ELLIPSOID:
        return [(mg.Ellipsoid(list(size)), np.eye(4))]
    if kind in (mujoco.mjtGeom.mjGEOM_CYLINDER, mujoco.mjtGeom.mjGEOM_CAPSULE):
        out: list[tuple[mg.Geometry, FloatArray]] = [(mg.Cylinder(2.0 * float(size[1]), float(size[0])), _rx90())]
        if kind == mujoco.mjtGeom.mjGEOM_CAPSULE:
            for sign in (-1.0, 1.0):
                T = np.eye(4)
                T[2, 3] = sign * size[1]
                out.append((mg.Sphere(float(size[0])), T))
        return out
    return []


def _matrix(pos: FloatArray, mat: FloatArray) -> FloatArray:
    T = np.eye(4)
    T[:3, :3] = mat
    T[:3, 3] = pos
    return T


def _quat_xyzw(mats: FloatArray) -> FloatArray:
    """(F, 3, 3) rotation matrices -> (F, 4) quaternions [x, y, z, w] (three.js order), sign-continuous."""
    out = np.empty((len(mats), 4))
    q = np.empty(4)
    for i, R in enumerate(mats):
        mujoco.mju_mat2Quat(q, np.ascontiguousarray(R).reshape(-1))
        out[i] = [q[1], q[2], q[3], q[0]]
        if i and np.dot(out[i], out[i - 1]) < 0.0:
            out[i] = -out[i]
    return out


def _keep(values: FloatArray) -> np.ndarray:
    """Frames to keep: the first, the last, and any that differs from a neighbour."""
    n = len(values)
    keep = np.zeros(n, dtype=bool)
    keep[[0, -1]] = True
    if n > 2:
        d_prev = np.abs(values[1:-1] - values[:-2]).max(axis=1) > POSE_TOLERANCE
        d_next = np.abs(values[1:-1] - values[2:]).max(axis=1) > POSE_TOLERANCE
        keep[1:-1] = d_prev | d_next
    return keep


def _pack(cmd: Any, ids: Iterator[int] | None = None) -> bytes:
    if isinstance(cmd, SetObject):
        # meshcat names objects by time-based uuid1: number them instead, so a run gives the same page every time.
        for element in (cmd.object, cmd.object.geometry, cmd.object.material):
            element.uuid = f"ur3hanoi-{next(ids if ids is not None else _UUIDS)}"
    return bytes(umsgpack.packb(cmd.lower() if hasattr(cmd, "lower") else cmd))


def _tower_pads(station: Station, ids: Iterator[int]) -> list[bytes]:
    """A thin light pad under every slot's bottom face, so empty towers show where they are."""
    out = []
    centers = slot_centers(station)
    s = station.block_size
    for t in range(centers.shape[0]):
        for h in range(centers.shape[1]):
            c = centers[t, h]
            path = ROOT.append(f"towers/t{t + 1}h{h + 1}")
            out.append(_pack(SetObject(mg.Box([1.3 * s, 1.3 * s, 0.001]),
                                       mg.MeshLambertMaterial(color=0xDDDDDD), path), ids))
            T = np.eye(4)
            T[:3, 3] = [c[0], c[1], c[2] - 0.5 * s + 0.0006]
            out.append(_pack(SetTransform(T, path)))
    return out


def camera_commands(station: Station, distance: float = 1.1, azimuth_deg: float = 200.0,
                    elevation_deg: float = -30.0) -> list[bytes]:
    """meshcat's camera aimed like the video's (MuJoCo free-camera convention: azimuth/elevation [deg]), orbiting
    the point between the robot base and the towers."""
    pts = slot_centers(station).reshape(-1, 3)
    lookat = 0.5 * (np.mean(pts, axis=0) + np.asarray(station.base_xyz)) + np.array([0.0, 0.0, 0.1])
    az, el = np.radians(azimuth_deg), np.radians(elevation_deg)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    offset = -distance * forward  # camera - lookat [m, world, z up]
    T = np.eye(4)
    T[:3, 3] = lookat
    cams = McPath(("Cameras", "default"))
    # The camera's own position is in meshcat's y-up "rotated" frame: (x, z, -y) of the world offset.
    return [_pack(SetProperty("visible", False, McPath(("Grid",)))),  # meshcat's grid at z = 0: not the table
            _pack(SetProperty("visible", False, McPath(("Axes",)))),
            _pack(SetTransform(T, cams)),
            _pack(SetProperty("position", [float(offset[0]), float(offset[2]), float(-offset[1])],
                              cams.append("rotated/<object>")))]


def scene_commands(model: mujoco.MjModel, station: Station, track: PoseTrack) -> list[bytes]:
    """Packed meshcat commands: objects, their first pose, the camera, and the animation (not started). The same
    inputs give the same bytes."""
    ids = itertools.count()
    cmds: list[bytes] = []
    clips = []
    for i, g in enumerate(track.geoms):
        name = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) or f"geom{int(g)}"
        node = ROOT.append(f"geoms/{name}")
        rgba = model.geom_rgba[g]
        for j, (shape, T_geom_shape) in enumerate(_shapes(model, int(g))):
            material = mg.MeshPhongMaterial(color=_hex(rgba), opacity=float(rgba[3]), transparent=bool(rgba[3] < 1))
            path = node.append(f"shape{j}")
            cmds.append(_pack(SetObject(shape, material, path), ids))
            cmds.append(_pack(SetTransform(T_geom_shape, path)))
        cmds.append(_pack(SetTransform(_matrix(track.pos[0, i], track.mat[0, i]), node)))
        pos = track.pos[:, i]
        quat = _quat_xyzw(track.mat[:, i])
        moving = max(np.abs(pos - pos[0]).max(), np.abs(quat - quat[0]).max()) > POSE_TOLERANCE
        if not moving:
            continue
        keep = _keep(np.hstack([pos, quat]))
        times = track.t[keep].astype(np.float32)
        clips.append({"path": node.lower(), "clip": {"fps": 1.0, "name": "default", "tracks": [
            {"name": ".position", "type": "vector3", "times": times.tolist(),
             "values": pos[keep].reshape(-1).tolist()},
            {"name": ".quaternion", "type": "quaternion", "times": times.tolist(),
             "values": quat[keep].reshape(-1).tolist()},
        ]}})
    cmds += _tower_pads(station, ids)
    cmds += camera_commands(station)
    if clips:
        cmds.append(_pack({"type": "set_animation", "path": "", "animations": clips,
                           "options": {"play": False, "repetitions": 1}}))
    return cmds
