"""ur3hanoi.sim.render: offscreen frames, and clear errors where no display or video backend exists."""

from __future__ import annotations

from pathlib import Path

import pytest

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
