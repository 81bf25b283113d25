"""Seeing a run: offscreen rendering to PNG frames or an MP4 (:class:`OffscreenRecorder`) and MuJoCo's interactive
viewer (:class:`ViewerSink`). Both are frame sinks for :func:`ur3hanoi.sim.run_plan` (``frames=``).

Headless machines need ``MUJOCO_GL=egl`` (or ``osmesa``) set before MuJoCo is imported.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from ur3hanoi.errors import SimulationError
from ur3hanoi.sim.scene import slot_centers
from ur3hanoi.station import Station


@dataclass(frozen=True)
class CameraConfig:
    """Offscreen camera: image size [px], frame rate [Hz], and a free camera aimed at the towers.

    Attributes:
        distance: [m] from the look-at point; azimuth, elevation: [deg], MuJoCo's free-camera convention.
    """

    width: int = 640
    height: int = 480
    fps: float = 30.0
    distance: float = 1.1
    azimuth: float = 200.0
    elevation: float = -30.0


def _free_camera(station: Station, cam: CameraConfig) -> mujoco.MjvCamera:
    c = mujoco.MjvCamera()
    c.type = mujoco.mjtCamera.mjCAMERA_FREE
    pts = slot_centers(station).reshape(-1, 3)
    c.lookat[:] = 0.5 * (np.mean(pts, axis=0) + np.asarray(station.base_xyz)) + np.array([0.0, 0.0, 0.1])
    c.distance, c.azimuth, c.elevation = cam.distance, cam.azimuth, cam.elevation
    return c


class OffscreenRecorder:
    """Renders frames offscreen (``mujoco.Renderer``) into PNG files (``frames_dir``) or an MP4 (``video``).

    Headless machines need ``MUJOCO_GL=egl`` (or ``osmesa``) set before MuJoCo is imported. MP4 needs
    ``imageio`` and ``imageio-ffmpeg``; PNG needs only Pillow. Use as a context manager (it closes the renderer
    and finishes the file).
    """

    def __init__(self, station: Station, model: mujoco.MjModel, frames_dir: Path | None = None,
                 video: Path | None = None, camera: CameraConfig | None = None) -> None:
        if (frames_dir is None) == (video is None):
            raise SimulationError("give exactly one of a frames directory or a video file")
        self.cam_cfg = camera if camera is not None else CameraConfig()
        self.fps = self.cam_cfg.fps
        self.frames_dir, self.video = frames_dir, video
        self.count = 0
        self._writer: Any = None
        if video is not None:
            try:
                import imageio.v2 as imageio  # optional: imageio + imageio-ffmpeg
            except ImportError:
                raise SimulationError(f"cannot write the video {video}: it needs the packages imageio and "
                                      "imageio-ffmpeg (not installed); write PNG frames (frames_dir) instead") from None
            video.parent.mkdir(parents=True, exist_ok=True)
            try:
                self._writer = imageio.get_writer(str(video), fps=self.fps, codec="libx264", quality=7,
                                                  macro_block_size=8)
            except Exception as exc:  # imageio raises several types for a missing ffmpeg backend
                raise SimulationError(f"cannot write {video}: {exc}") from None
        else:
            assert frames_dir is not None
            frames_dir.mkdir(parents=True, exist_ok=True)
        try:
            self.renderer = mujoco.Renderer(model, self.cam_cfg.height, self.cam_cfg.width)
        except Exception as exc:  # no OpenGL context: the message says which backend failed
            if self._writer is not None:
                self._writer.close()
            raise SimulationError(f"offscreen rendering is unavailable ({exc}); on a headless machine set "
                                  "MUJOCO_GL=egl (libegl1) or MUJOCO_GL=osmesa (libosmesa6)") from None
        self.camera = _free_camera(station, self.cam_cfg)

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self.renderer.update_scene(data, self.camera)
        pixels = self.renderer.render()
        if self._writer is not None:
            self._writer.append_data(pixels)
        else:
            from PIL import Image

            assert self.frames_dir is not None
            Image.fromarray(pixels).save(self.frames_dir / f"frame_{self.count:05d}.png")
        self.count += 1

    def close(self) -> None:
        self.renderer.close()
        if self._writer is not None:
            self._writer.close()
            self._writer = None

    def __enter__(self) -> OffscreenRecorder:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def display_available() -> str | None:
    """None when an interactive viewer can open, else the reason it cannot."""
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no display (DISPLAY and WAYLAND_DISPLAY are unset)"
    return None


class ViewerSink:
    """Passive MuJoCo viewer synced at ``fps`` (the executor runs in real time while it is open)."""

    fps = 60.0

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        import mujoco.viewer

        reason = display_available()
        if reason is not None:
            raise SimulationError(f"the MuJoCo viewer cannot open: {reason}")
        try:
            self.handle = mujoco.viewer.launch_passive(model, data)
        except Exception as exc:
            raise SimulationError(f"the MuJoCo viewer cannot open: {exc}") from None

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        if self.handle.is_running():
            self.handle.sync()

    def close(self) -> None:
        self.handle.close()
