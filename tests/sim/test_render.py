"""ur3hanoi.sim.render: offscreen frames, and clear errors where no display or video backend exists."""

from __future__ import annotations

import os
import signal
import stat
from pathlib import Path

import mujoco
import numpy as np
import pytest
from PIL import Image

from tests.support.sim_helpers import STATIONS
from ur3hanoi.errors import OutputError, SimulationError
from ur3hanoi.sim import (
    CameraConfig,
    OffscreenRecorder,
    TaskScene,
    ViewerSink,
    build_task_scene,
    display_available,
)


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


# ------------------------------------------------------------------------------------ outputs: atomic and safe

TINY = CameraConfig(width=32, height=24, fps=10.0)


def _recorder(**kwargs: object) -> tuple[OffscreenRecorder, TaskScene]:
    scene = build_task_scene(STATIONS["lab_sim"], 0, 1)
    try:
        return OffscreenRecorder(STATIONS["lab_sim"], scene.model, camera=TINY, **kwargs), scene  # type: ignore[arg-type]
    except SimulationError as exc:
        pytest.skip(str(exc))


def _offer(rec: OffscreenRecorder, scene: TaskScene, n: int) -> None:
    for i in range(n):
        scene.data.time = i / TINY.fps
        rec(scene.model, scene.data)


def _ffmpeg_children() -> list[int]:
    """The pids of this process's ffmpeg children (imageio-ffmpeg's encoder)."""
    pids = []
    for task in Path(f"/proc/{os.getpid()}/task").iterdir():
        for pid in (task / "children").read_text().split():
            if "ffmpeg" in Path(f"/proc/{pid}/cmdline").read_text(errors="replace"):
                pids.append(int(pid))
    return pids


def test_an_interrupted_video_leaves_the_existing_file_as_it_was(tmp_path: Path) -> None:
    video = tmp_path / "run.mp4"
    video.write_bytes(b"the previous video")
    rec, scene = _recorder(video=video)
    with pytest.raises(KeyboardInterrupt), rec:
        _offer(rec, scene, 3)
        raise KeyboardInterrupt  # Ctrl-C in the middle of the run
    assert video.read_bytes() == b"the previous video"
    assert _listing(tmp_path) == ["run.mp4"]


def test_a_failed_encoder_leaves_the_existing_file_as_it_was(tmp_path: Path) -> None:
    video = tmp_path / "run.mp4"
    video.write_bytes(b"the previous video")
    rec, scene = _recorder(video=video)
    with pytest.raises(SimulationError, match=r"cannot write .*run\.mp4") as info, rec:
        _offer(rec, scene, 2)
        for pid in _ffmpeg_children():
            os.kill(pid, signal.SIGKILL)  # ffmpeg dies mid-video
        _offer(rec, scene, 30)
    assert "\n" not in str(info.value)
    assert video.read_bytes() == b"the previous video"
    assert _listing(tmp_path) == ["run.mp4"]


def test_a_video_named_like_an_option_is_a_file(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import imageio_ffmpeg

    monkeypatch.chdir(tmp_path)
    rec, scene = _recorder(video=Path("-x.mp4"))  # as `--video=-x.mp4` gives it
    with rec:
        _offer(rec, scene, 3)
    assert imageio_ffmpeg.count_frames_and_secs(str(tmp_path / "-x.mp4"))[0] == 3
    assert _listing(tmp_path) == ["-x.mp4"]


def test_a_finished_video_replaces_the_old_one_keeping_its_permissions(tmp_path: Path) -> None:
    import imageio_ffmpeg

    video = tmp_path / "run.webm"
    video.write_bytes(b"old")
    video.chmod(0o640)
    rec, scene = _recorder(video=video)
    with rec:
        _offer(rec, scene, 2)
    assert imageio_ffmpeg.count_frames_and_secs(str(video))[0] == 2
    assert stat.S_IMODE(video.stat().st_mode) == 0o640 and _listing(tmp_path) == ["run.webm"]


def test_interrupted_frames_leave_no_folder_and_an_existing_one_as_it_was(tmp_path: Path) -> None:
    new = tmp_path / "new"
    rec, scene = _recorder(frames_dir=new)
    with pytest.raises(KeyboardInterrupt), rec:
        _offer(rec, scene, 2)
        raise KeyboardInterrupt
    assert _listing(tmp_path) == []
    old = tmp_path / "old"
    old.mkdir()
    for name in ("frame_00000.png", "frame_00001.png", "frame_00002.png", "notes.txt"):
        (old / name).write_bytes(b"previous run")
    rec, scene = _recorder(frames_dir=old)
    with pytest.raises(KeyboardInterrupt), rec:
        _offer(rec, scene, 2)
        raise KeyboardInterrupt
    assert {p.name: p.read_bytes() for p in old.iterdir()} == {
        name: b"previous run" for name in ("frame_00000.png", "frame_00001.png", "frame_00002.png", "notes.txt")}


def test_finished_frames_replace_an_earlier_runs_frames_only(tmp_path: Path) -> None:
    old = tmp_path / "frames"
    old.mkdir()
    for name in ("frame_00000.png", "frame_00001.png", "frame_00002.png", "notes.txt"):
        (old / name).write_bytes(b"previous run")
    rec, scene = _recorder(frames_dir=old)
    with rec:
        _offer(rec, scene, 2)
    assert _listing(old) == ["frame_00000.png", "frame_00001.png", "notes.txt"]
    assert Image.open(old / "frame_00001.png").size == (32, 24) and (old / "notes.txt").read_bytes() == b"previous run"
    rec, scene = _recorder(frames_dir=tmp_path / "fresh")  # a new folder is renamed into place
    with rec:
        _offer(rec, scene, 1)
    assert _listing(tmp_path) == ["frames", "fresh"] and _listing(tmp_path / "fresh") == ["frame_00000.png"]


@pytest.mark.parametrize(("kind", "match"), [
    ("proc", "does not accept new files"),
    ("missing", "does not exist"),
])
def test_unwritable_outputs_are_refused_before_rendering(tmp_path: Path, kind: str, match: str) -> None:
    scene = build_task_scene(STATIONS["lab_sim"], 0, 1)
    target = Path("/proc/x.mp4") if kind == "proc" else tmp_path / "no" / "x.mp4"
    with pytest.raises(OutputError, match=match):
        OffscreenRecorder(STATIONS["lab_sim"], scene.model, camera=TINY, video=target)
    with pytest.raises(OutputError, match=match):
        OffscreenRecorder(STATIONS["lab_sim"], scene.model, camera=TINY, frames_dir=target.with_suffix(""))
    assert _listing(tmp_path) == []


def _listing(directory: Path) -> list[str]:
    return sorted(p.name for p in directory.iterdir())


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
