"""Recording a run for the replay page: :class:`PoseRecorder` samples the world pose of every drawn geom at ``fps``
(a frame sink for :func:`ur3hanoi.sim.run_plan`), :class:`SinkTee` feeds it and a video recorder from one run, and
:func:`record_plan` poses the scene along a plan without physics (``ur3hanoi plan --html``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mujoco
import numpy as np
import numpy.typing as npt

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import SimulationError
from ur3hanoi.plan.types import Plan
from ur3hanoi.sim.executor import FrameSink
from ur3hanoi.sim.scene import TaskScene

DRAWN_GROUPS = (0, 1, 2)
"""MuJoCo geom groups drawn by the replay (MuJoCo's viewer shows the same ones by default)."""


def drawn_geoms(model: mujoco.MjModel) -> npt.NDArray[np.int_]:
    """Ids of the geoms the replay draws: visible (alpha > 0) in :data:`DRAWN_GROUPS`, infinite planes left out
    (the page has its own floor grid)."""
    ids = [g for g in range(model.ngeom)
           if model.geom_group[g] in DRAWN_GROUPS and model.geom_rgba[g, 3] > 0
           and model.geom_type[g] != mujoco.mjtGeom.mjGEOM_PLANE]
    return np.array(ids, dtype=np.int_)


@dataclass(frozen=True)
class PoseTrack:
    """World poses of the drawn geoms over time.

    Attributes:
        geoms: (G,) MuJoCo geom ids.
        t: (F,) sim time of each frame [s].
        pos: (F, G, 3) geom origin [m, world].
        mat: (F, G, 3, 3) geom orientation (columns = geom axes in world).
    """

    geoms: npt.NDArray[np.int_]
    t: FloatArray
    pos: FloatArray
    mat: FloatArray


class PoseRecorder:
    """A frame sink that samples the pose of every drawn geom at ``fps`` [Hz] of sim time; ``count`` frames so far."""

    def __init__(self, model: mujoco.MjModel, fps: float = 30.0) -> None:
        if not fps > 0:
            raise SimulationError(f"replay frame rate {fps!r} Hz is invalid: expected a positive rate")
        self.fps = float(fps)
        self.geoms = drawn_geoms(model)
        self._t: list[float] = []
        self._pos: list[FloatArray] = []
        self._mat: list[FloatArray] = []

    @property
    def count(self) -> int:
        return len(self._t)

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self._t.append(float(data.time))
        self._pos.append(data.geom_xpos[self.geoms].copy())
        self._mat.append(data.geom_xmat[self.geoms].reshape(-1, 3, 3).copy())

    def track(self) -> PoseTrack:
        if not self._t:
            raise SimulationError("the replay recorded no frame")
        return PoseTrack(self.geoms, np.array(self._t), np.stack(self._pos), np.stack(self._mat))

    def close(self) -> None:
        """Nothing to release (a frame sink's interface)."""


class SinkTee:
    """One frame sink feeding several, each at its own rate: the executor calls it at the highest ``fps`` and each
    sink receives the frames due on its own schedule (``1 / fps`` apart, from t = 0)."""

    def __init__(self, sinks: Sequence[FrameSink]) -> None:
        if not sinks:
            raise SimulationError("SinkTee needs at least one frame sink")
        self.sinks = list(sinks)
        self.fps = max(s.fps for s in self.sinks)
        self._next = [0.0] * len(self.sinks)

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        t = float(data.time)
        for i, sink in enumerate(self.sinks):
            if t + 1e-9 >= self._next[i]:
                sink(model, data)
                self._next[i] += 1.0 / sink.fps
                if self._next[i] <= t:  # a slower caller than this sink: never queue a backlog
                    self._next[i] = t + 1.0 / sink.fps


def record_plan(plan: Plan, scene: TaskScene, fps: float = 30.0) -> PoseTrack:
    """Pose ``scene`` along ``plan`` without physics, at ``fps`` [Hz]: the arm at the planned joints, a block fixed
    to the cup from the sample the suction turns on next to it until it turns off (the plan as intended).

    The scene must be the plan's (:func:`ur3hanoi.sim.build_task_scene` with its start tower and blocks).
    """
    m, d = scene.model, scene.data
    tr = plan.trajectory
    rec = PoseRecorder(m, fps)
    cup = scene.cup_body
    held: int | None = None
    rel = np.eye(4)  # T_cup_block while held
    n = len(tr.t)
    times = np.arange(0.0, float(tr.t[-1]) + 1e-9, 1.0 / fps)
    samples = np.minimum(np.rint(times * tr.rate_hz).astype(int), n - 1)
    k_done = 0
    suction = tr.suction.tolist()
    move_of = tr.move_index.tolist()

    def pose(body: int) -> FloatArray:
        T = np.eye(4)
        T[:3, :3] = d.xmat[body].reshape(3, 3)
        T[:3, 3] = d.xpos[body]
        return T

    def _place(block: int, T_world_block: FloatArray) -> None:
        adr = scene.block_qadr[block]
        d.qpos[adr:adr + 3] = T_world_block[:3, 3]
        quat = np.empty(4)
        mujoco.mju_mat2Quat(quat, T_world_block[:3, :3].reshape(-1))
        d.qpos[adr + 3:adr + 7] = quat

    for t, k in zip(times, samples, strict=True):
        # Walk the suction transitions between the previous frame's sample and this one.
        for j in range(k_done, k + 1):
            d.qpos[scene.arm_qadr] = tr.q[j]
            if suction[j] and held is None and move_of[j] >= 0:
                mujoco.mj_kinematics(m, d)
                block = plan.moves[move_of[j]].block
                if block in scene.block_body:
                    held = block
                    rel = np.linalg.inv(pose(cup)) @ pose(scene.block_body[block])
            elif not suction[j] and held is not None:
                # Put the block down where the cup releases it (not where it was at the last frame, which may lie
                # before the arm reached the contact pose).
                mujoco.mj_kinematics(m, d)
                _place(held, pose(cup) @ rel)
                held = None
        k_done = k + 1
        d.qpos[scene.arm_qadr] = tr.q[k]
        mujoco.mj_kinematics(m, d)
        if held is not None:
            _place(held, pose(cup) @ rel)
            mujoco.mj_kinematics(m, d)
        d.time = float(t)
        rec(m, d)
    return rec.track()
