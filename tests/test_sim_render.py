"""ur3hanoi.sim.render: offscreen frames, and clear errors where no display or video backend exists."""

from __future__ import annotations

from pathlib import Path

import mujoco
import numpy as np
import pytest
from PIL import Image

from ur3hanoi.errors import SimulationError
from ur3hanoi.sim import CameraConfig, OffscreenRecorder, ViewerSink, build_task_scene, display_available

from .sim_helpers import STATIONS


def test_offscreen_frames(tmp_path: Path) -> None:
    station = STATIONS["lab_sim"]
    scene = build_task_scene(station, 0, 3)
    try:
        rec = OffscreenRecorder(station, scene.model, frames_dir=tmp_path, camera=CameraConfig(width=320, height=240))
    except SimulationError as exc:
        pytest.skip(str(exc))
    with rec:
        rec(scene.model, scene.data)
        rec(scene.model, scene.data)
    assert rec.count == 2
    assert (tmp_path / "frame_00000.png").stat().st_size > 1000 and (tmp_path / "frame_00001.png").is_file()


@pytest.mark.parametrize("both", [True, False], ids=["both", "neither"])
def test_recorder_needs_exactly_one_output(tmp_path: Path, both: bool) -> None:
    station = STATIONS["lab_sim"]
    scene = build_task_scene(station, 0, 1)
    video = tmp_path / "v.mp4" if both else None
    frames = tmp_path if both else None
    with pytest.raises(SimulationError, match="exactly one of a frames directory or a video file"):
        OffscreenRecorder(station, scene.model, frames_dir=frames, video=video)


def test_no_display_is_reported_without_cli_flags(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    reason = display_available()
    assert reason is not None and "no display" in reason and "--" not in reason
    scene = build_task_scene(STATIONS["lab_sim"], 0, 1)
    with pytest.raises(SimulationError, match="the MuJoCo viewer cannot open: no display") as info:
        ViewerSink(scene.model, scene.data)
    assert "--" not in str(info.value)


def test_display_variable_makes_a_display_available(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("WAYLAND_DISPLAY", "wayland-0")
    assert display_available() is None


def _frames(directory: Path) -> list[np.ndarray]:
    return [np.asarray(Image.open(p).convert("RGB")).astype(int) for p in sorted(directory.glob("frame_*.png"))]


def test_parallel_workers_render_the_same_frames_in_order(tmp_path: Path) -> None:
    """Frames rendered by worker processes equal the ones rendered in the run, in the same order; progress counts
    every frame up to 1."""
    station = STATIONS["lab_sim"]
    scene = build_task_scene(station, 0, 3)
    cam = CameraConfig(width=160, height=120)
    data = scene.data
    qpos0 = data.qpos.copy()
    poses = [qpos0.copy() for _ in range(5)]
    for i, q in enumerate(poses):
        q[scene.arm_qadr[0]] += 0.3 * i  # the base turns a little more each frame
    outputs = {}
    reports: list[tuple[float, str]] = []
    for workers in (1, 2):
        out = tmp_path / f"w{workers}"
        try:
            rec = OffscreenRecorder(station, scene.model, frames_dir=out, camera=cam, workers=workers,
                                    progress=lambda f, label: reports.append((f, label)))
        except SimulationError as exc:
            pytest.skip(str(exc))
        with rec:
            for i, q in enumerate(poses):
                data.qpos[:] = q
                data.time = i / cam.fps
                mujoco.mj_forward(scene.model, data)
                rec(scene.model, data)
        assert rec.count == len(poses)
        outputs[workers] = _frames(out)
    assert len(outputs[2]) == len(outputs[1]) == 5
    for a, b in zip(outputs[1], outputs[2], strict=True):
        assert np.abs(a - b).max() <= 2  # same GL driver, same state: the same picture
    assert any(np.abs(outputs[1][0] - outputs[1][4]).max(axis=-1).ravel() > 40)  # and the frames differ
    assert [f for f, _ in reports] == pytest.approx([0.2, 0.4, 0.6, 0.8, 1.0])
    assert reports[-1][1] == "frame 5/5"


def test_interrupted_parallel_recording_writes_nothing(tmp_path: Path) -> None:
    station = STATIONS["lab_sim"]
    scene = build_task_scene(station, 0, 3)
    try:
        rec = OffscreenRecorder(station, scene.model, frames_dir=tmp_path, camera=CameraConfig(width=64, height=48),
                                workers=2)
    except SimulationError as exc:
        pytest.skip(str(exc))
    with pytest.raises(KeyboardInterrupt), rec:
        rec(scene.model, scene.data)
        raise KeyboardInterrupt
    assert rec.count == 0 and not list(tmp_path.glob("frame_*.png"))


def test_quality_settings_reach_the_renderer(tmp_path: Path) -> None:
    """The shadow map size and multisampling are the model's (read by MuJoCo when the renderer is made)."""
    station = STATIONS["lab_sim"]
    scene = build_task_scene(station, 0, 3)
    try:
        OffscreenRecorder(station, scene.model, frames_dir=tmp_path,
                          camera=CameraConfig(width=64, height=48, shadow_size=512, multisamples=2)).close()
    except SimulationError as exc:
        pytest.skip(str(exc))
    assert scene.model.vis.quality.shadowsize == 512 and scene.model.vis.quality.offsamples == 2
