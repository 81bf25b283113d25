"""ur3hanoi.sim.render options: the video formats by extension, image size beyond MuJoCo's default framebuffer, the
frame rate and the sim-time window. Tiny images and few frames keep it fast."""

from __future__ import annotations

from pathlib import Path

import mujoco
import pytest
from PIL import Image

from tests.support.sim_helpers import STATIONS
from ur3hanoi.errors import OutputError, SimulationError
from ur3hanoi.sim import (
    VIDEO_FORMATS,
    CameraConfig,
    OffscreenRecorder,
    TaskScene,
    build_task_scene,
    check_video_path,
)

TINY = CameraConfig(width=32, height=24, fps=10.0)


@pytest.fixture(scope="module")
def scene() -> TaskScene:
    return build_task_scene(STATIONS["lab_sim"], 0, 3)


def _recorder(scene: TaskScene, **kwargs: object) -> OffscreenRecorder:
    try:
        return OffscreenRecorder(STATIONS["lab_sim"], scene.model, **kwargs)  # type: ignore[arg-type]
    except SimulationError as exc:
        if "offscreen rendering is unavailable" in str(exc):
            pytest.skip(str(exc))
        raise


def _offer(rec: OffscreenRecorder, scene: TaskScene, times: list[float]) -> None:
    """Offer a frame at each sim time [s], as the executor does at its frame rate."""
    with rec:
        for t in times:
            scene.data.time = t
            rec(scene.model, scene.data)


def test_only_frames_inside_the_window_are_written(scene: TaskScene, tmp_path: Path) -> None:
    rec = _recorder(scene, frames_dir=tmp_path, camera=TINY, t_from=0.3, t_to=0.5)
    _offer(rec, scene, [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6])
    assert rec.count == 3 and sorted(p.name for p in tmp_path.iterdir()) == [
        "frame_00000.png", "frame_00001.png", "frame_00002.png"]
    assert Image.open(tmp_path / "frame_00000.png").size == (32, 24)


def test_a_window_without_an_end_runs_to_the_end(scene: TaskScene, tmp_path: Path) -> None:
    rec = _recorder(scene, frames_dir=tmp_path, camera=TINY, t_from=0.15)
    _offer(rec, scene, [0.0, 0.1, 0.2, 0.3])
    assert rec.count == 2 and rec.fps == TINY.fps


def test_every_video_extension_is_accepted_in_any_case() -> None:
    for ext in VIDEO_FORMATS:
        assert check_video_path(Path(f"run{ext}")) is check_video_path(Path(f"RUN{ext.upper()}"))


# One per encoder (.mkv and .mov share .mp4's H.264): each opens an offscreen context, the costly part.
@pytest.mark.parametrize("ext", [".mp4", ".webm", ".gif"])
def test_every_video_encoder_holds_the_frames_written(scene: TaskScene, tmp_path: Path, ext: str) -> None:
    import imageio_ffmpeg

    video = tmp_path / f"run{ext.upper() if ext == '.mp4' else ext}"  # the extension is case-insensitive
    rec = _recorder(scene, video=video, camera=TINY)
    _offer(rec, scene, [0.0, 0.1, 0.2, 0.3])
    assert rec.count == 4
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(video))
    assert frames == 4


def test_no_frame_in_the_window_leaves_no_video(scene: TaskScene, tmp_path: Path) -> None:
    video = tmp_path / "empty.mp4"
    rec = _recorder(scene, video=video, camera=TINY, t_from=5.0)
    _offer(rec, scene, [0.0, 0.1])
    assert rec.count == 0 and not video.exists()


def test_images_wider_than_the_models_framebuffer(tmp_path: Path) -> None:
    scene = build_task_scene(STATIONS["lab_sim"], 0, 1)  # its own model: the recorder grows the framebuffer
    width = int(scene.model.vis.global_.offwidth) + 64  # the scene's XML sets 1280 x 720
    rec = _recorder(scene, frames_dir=tmp_path, camera=CameraConfig(width=width, height=32))
    _offer(rec, scene, [0.0])
    assert Image.open(tmp_path / "frame_00000.png").size == (width, 32)
    assert scene.model.vis.global_.offwidth >= width


@pytest.mark.parametrize("name", ["run.avi", "run.mp5", "run", "run.mp4.part"])
def test_an_unknown_video_extension_is_refused_listing_the_valid_ones(name: str) -> None:
    with pytest.raises(OutputError) as info:
        check_video_path(Path(name))
    msg = str(info.value)
    assert msg.endswith("expected one of .mp4, .mkv, .mov, .webm, .gif") and "\n" not in msg and "--" not in msg


def test_the_recorder_refuses_an_unknown_extension_before_writing(scene: TaskScene, tmp_path: Path) -> None:
    with pytest.raises(OutputError):
        OffscreenRecorder(STATIONS["lab_sim"], scene.model, video=tmp_path / "run.avi", camera=TINY)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("ext", [".mp4", ".webm"])
def test_odd_sizes_are_refused_for_subsampled_video(scene: TaskScene, tmp_path: Path, ext: str) -> None:
    with pytest.raises(SimulationError, match="expected an even width and height"):
        OffscreenRecorder(STATIONS["lab_sim"], scene.model, video=tmp_path / f"v{ext}",
                          camera=CameraConfig(width=33, height=24))


@pytest.mark.parametrize(("t_from", "t_to"), [(1.0, 1.0), (2.0, 1.0), (-1.0, None), (float("nan"), None)])
def test_an_empty_or_invalid_window_is_refused(scene: TaskScene, tmp_path: Path, t_from: float,
                                               t_to: float | None) -> None:
    with pytest.raises(SimulationError, match="time window"):
        OffscreenRecorder(STATIONS["lab_sim"], scene.model, frames_dir=tmp_path, camera=TINY, t_from=t_from,
                          t_to=t_to)


def test_mujoco_default_framebuffer_is_what_the_recorder_grows() -> None:
    # The reason for growing it: a model without a <visual> setting offers 640x480 offscreen.
    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    assert (model.vis.global_.offwidth, model.vis.global_.offheight) == (640, 480)
