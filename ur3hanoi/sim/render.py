"""Seeing a run: offscreen rendering to PNG frames or a video (:class:`OffscreenRecorder`) and MuJoCo's interactive
viewer (:class:`ViewerSink`). Both are frame sinks for :func:`ur3hanoi.sim.run_plan` (``frames=``).

Videos are encoded by the ffmpeg binary of the ``imageio-ffmpeg`` wheel; the container follows the file's
extension (:data:`VIDEO_FORMATS`: ``.mp4``, ``.mkv``, ``.mov`` with H.264, ``.webm`` with VP9, ``.gif``), and
:func:`check_video_path` refuses any other extension before anything is simulated. The recorder renders only
inside its time window (``t_from``..``t_to`` [s] of sim time) and sizes MuJoCo's offscreen framebuffer to the image.

Outputs go through :mod:`ur3hanoi.io.atomic`: ffmpeg writes a temporary file beside the video (same extension, an
absolute path, so a name like ``-x.mp4`` is never an ffmpeg option) that replaces the video only when the recorder
is closed normally; frames go to a temporary folder moved into place on close. An error, or leaving the ``with``
block by an exception, discards them: an existing video or folder stays as it was.

MuJoCo renders with the OpenGL platform it was imported with (``MUJOCO_GL``): call
:func:`ur3hanoi.opengl.use_platform` first (the commands do), or set ``MUJOCO_GL``.
"""

from __future__ import annotations

import contextlib
import math
import os
import re
import signal
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from ur3hanoi.errors import OutputError, SimulationError, Ur3HanoiError, printable, quote
from ur3hanoi.io.atomic import PendingDir, PendingFile, check_output, check_output_dir
from ur3hanoi.opengl import display_available, offscreen_renderer
from ur3hanoi.sim.scene import slot_centers
from ur3hanoi.station.calibration import Station


@dataclass(frozen=True)
class VideoFormat:
    """How a video container is encoded by ffmpeg: ``codec``, output pixel format, the imageio-ffmpeg ``quality``
    (0-10; None: codec default, ``params`` set it) and extra ffmpeg output ``params``."""

    codec: str
    pix_fmt: str = "yuv420p"
    quality: float | None = 7.0
    params: tuple[str, ...] = ()


# H.264 at x264's "veryfast" preset: 4.6 instead of 6.9 ms of CPU a 640x480 frame, a smaller file at the same
# quality (bench/bench_render.py).
_H264 = VideoFormat("libx264", params=("-preset", "veryfast"))

VIDEO_FORMATS: dict[str, VideoFormat] = {
    ".mp4": _H264,
    ".mkv": _H264,
    ".mov": _H264,
    # VP9 needs an explicit constant quality (crf with a zero bitrate), or ffmpeg warns and picks one.
    ".webm": VideoFormat("libvpx-vp9", quality=None, params=("-crf", "32", "-b:v", "0")),
    # GIF: ffmpeg's own palette (pal8), no chroma subsampling, so any size works.
    ".gif": VideoFormat("gif", pix_fmt="pal8", quality=None),
}
"""The video file extensions :class:`OffscreenRecorder` writes (lower case), and their encoding."""

FRAME_NAME = re.compile(r"frame_\d{5,}\.png")
"""The names of PNG frames (``frame_00000.png``...): those of an earlier run in the folder are replaced."""


def check_video_path(video: str | Path) -> VideoFormat:
    """The encoding of ``video`` by its extension (case-insensitive).

    Raises:
        OutputError: the extension is not one of :data:`VIDEO_FORMATS` (the message lists them).
    """
    ext = Path(video).suffix.lower()
    fmt = VIDEO_FORMATS.get(ext)
    if fmt is None:
        got = f"extension {quote(ext)}" if ext else "no extension"
        raise OutputError(f"cannot write the video {printable(video)}: {got} is not a video format ur3hanoi writes: "
                          f"expected one of {', '.join(VIDEO_FORMATS)}")
    return fmt


def _first_line(exc: BaseException) -> str:
    """An encoder error in one line (imageio-ffmpeg appends the ffmpeg command and its output)."""
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__


@dataclass(frozen=True)
class CameraConfig:
    """Offscreen camera: image size [px], frame rate [Hz], and a free camera aimed at the towers.

    Attributes:
        width, height: image size [px]; videos other than GIF need even numbers (H.264/VP9 chroma subsampling).
        fps: frames per second of sim time [Hz] (at most the control rate: the executor offers a frame per cycle).
        distance: [m] from the look-at point; azimuth, elevation: [deg], MuJoCo's free-camera convention.
        shadow_size: side of the shadow map [px] (0: no shadows). MuJoCo's default 4096 costs most of a frame in
            software GL; at 1024 the arm's shadow on the table looks the same at 640x480 (see bench/bench_render.py).
        reflections: mirror the scene in reflective materials (the floor); off: a software-GL pass saved.
        multisamples: MSAA samples of the offscreen buffer (MuJoCo's default 4; 0 off: a few jagged edges, the
            largest saving after shadows).
    """

    width: int = 640
    height: int = 480
    fps: float = 30.0
    distance: float = 1.1
    azimuth: float = 200.0
    elevation: float = -30.0
    shadow_size: int = 1024
    reflections: bool = False
    multisamples: int = 0


def _lookat(station: Station) -> tuple[float, float, float]:
    """The camera's look-at point [m, world]: between the robot base and the towers, 0.1 m up."""
    pts = slot_centers(station).reshape(-1, 3)
    p = 0.5 * (np.mean(pts, axis=0) + np.asarray(station.base_xyz)) + np.array([0.0, 0.0, 0.1])
    return float(p[0]), float(p[1]), float(p[2])


def _camera(lookat: tuple[float, float, float], cam: CameraConfig) -> mujoco.MjvCamera:
    c = mujoco.MjvCamera()
    c.type = mujoco.mjtCamera.mjCAMERA_FREE
    c.lookat[:] = lookat
    c.distance, c.azimuth, c.elevation = cam.distance, cam.azimuth, cam.elevation
    return c


def _free_camera(station: Station, cam: CameraConfig) -> mujoco.MjvCamera:
    return _camera(_lookat(station), cam)


def _set_quality(model: mujoco.MjModel, cam: CameraConfig) -> None:
    """Size the offscreen framebuffer to the image and set the shadow map and multisampling (read when a renderer
    is created)."""
    vis = model.vis
    vis.global_.offwidth = max(vis.global_.offwidth, cam.width)
    vis.global_.offheight = max(vis.global_.offheight, cam.height)
    vis.quality.shadowsize = max(0, int(cam.shadow_size))
    vis.quality.offsamples = max(0, int(cam.multisamples))


def _draw(renderer: mujoco.Renderer, data: mujoco.MjData, camera: mujoco.MjvCamera, cam: CameraConfig) -> Any:
    """One frame: the scene of ``data`` seen by ``camera``, with the config's shadow and reflection flags."""
    renderer.update_scene(data, camera)
    flags = renderer.scene.flags
    flags[mujoco.mjtRndFlag.mjRND_SHADOW] = cam.shadow_size > 0
    flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = cam.reflections
    return renderer.render()


# A rendering worker process's state (set by _init_worker; one renderer per process).
_WORKER: dict[str, Any] = {}


def _init_worker(parent: int, model: mujoco.MjModel, lookat: tuple[float, float, float], cam: CameraConfig) -> None:
    from ur3hanoi.lifecycle import child_start

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent terminates the pool (SIGTERM) on a Ctrl-C
    child_start(parent)  # and the kernel does when the parent dies
    # One llvmpipe thread per process: the processes are the parallelism (read when the GL driver loads).
    os.environ.setdefault("LP_NUM_THREADS", "1")
    _WORKER["model"], _WORKER["data"] = model, mujoco.MjData(model)
    _WORKER["renderer"] = offscreen_renderer(model, cam.height, cam.width)
    _WORKER["camera"], _WORKER["cam"] = _camera(lookat, cam), cam


def _render_state(state: tuple[float, Any]) -> Any:
    """Render the joint state ``(t [s], qpos)`` in a worker process."""
    m, d = _WORKER["model"], _WORKER["data"]
    d.time, d.qpos[:] = state[0], state[1]
    mujoco.mj_forward(m, d)
    return np.ascontiguousarray(_draw(_WORKER["renderer"], d, _WORKER["camera"], _WORKER["cam"]))


class OffscreenRecorder:
    """Renders frames offscreen (``mujoco.Renderer``) into PNG files (``frames_dir``) or a video file (``video``).

    Only frames whose sim time lies in ``[t_from, t_to]`` [s] are rendered (``t_to`` None: to the end); ``count``
    is the number written. With ``workers`` > 1 the run only records each frame's joint state, and
    :meth:`render_pending` (called by the context manager on success) renders them in that many processes
    (``spawn``, one software-GL thread each), in order, reporting ``progress(fraction, label)`` per frame, while
    ffmpeg encodes in its own process. OpenGL: see the module docstring. A video needs ``imageio-ffmpeg`` (its
    wheel ships ffmpeg) and an extension of :data:`VIDEO_FORMATS`; PNG needs only Pillow. Use as a context manager
    (it closes the renderer and finishes the file, or :meth:`discard` s it when the block raises). The output is
    checked here (:mod:`ur3hanoi.io.atomic`) and written only on close.
    """

    def __init__(self, station: Station, model: mujoco.MjModel, frames_dir: Path | None = None,
                 video: Path | None = None, camera: CameraConfig | None = None, t_from: float = 0.0,
                 t_to: float | None = None, workers: int = 1,
                 progress: Callable[[float, str], None] | None = None) -> None:
        if (frames_dir is None) == (video is None):
            raise SimulationError("give exactly one of a frames directory or a video file")
        self.cam_cfg = camera if camera is not None else CameraConfig()
        cam = self.cam_cfg
        if not (cam.width >= 1 and cam.height >= 1 and math.isfinite(cam.fps) and cam.fps > 0):
            raise SimulationError(f"camera {cam.width}x{cam.height} px at {cam.fps!r} Hz is invalid: expected a "
                                  "positive size and frame rate")
        t_end = math.inf if t_to is None else t_to
        if not (math.isfinite(t_from) and t_from >= 0.0 and t_end > t_from):
            raise SimulationError(f"time window [{t_from!r}, {t_to!r}] s is invalid: expected 0 <= from < to")
        self.fps = cam.fps
        self.t_from, self.t_to = float(t_from), t_end
        self.frames_dir, self.video = frames_dir, video
        self.count = 0
        self._writer: Any = None
        self._video_format: VideoFormat | None = None
        self._pending: PendingFile | PendingDir | None = None
        if video is not None:
            fmt = check_video_path(video)
            if fmt.pix_fmt == "yuv420p" and (cam.width % 2 or cam.height % 2):
                raise SimulationError(f"a {video.suffix} video of {cam.width}x{cam.height} px is invalid: expected "
                                      "an even width and height")
            try:
                import imageio_ffmpeg  # optional: the "video" extra

                imageio_ffmpeg.get_ffmpeg_exe()
            except ImportError:
                raise SimulationError(f"cannot write the video {printable(video)}: it needs imageio-ffmpeg (not "
                                      "installed): pip install 'ur3hanoi[video]'; or write PNG frames (frames_dir)"
                                      ) from None
            except RuntimeError as exc:  # no ffmpeg binary found
                raise SimulationError(f"cannot write the video {printable(video)}: {exc}") from None
            self._video_format = fmt
            self._video_out = check_output(video)
        else:
            assert frames_dir is not None
            self._frames_out = check_output_dir(frames_dir)
        # MuJoCo's offscreen framebuffer is the model's (640x480 unless the XML says otherwise): make it fit.
        _set_quality(model, cam)
        self.model, self.lookat = model, _lookat(station)
        self.workers, self.progress = max(1, int(workers)), progress
        self._states: list[tuple[float, Any]] = []  # (t, qpos) of the frames to render in parallel at close()
        self.renderer = offscreen_renderer(model, cam.height, cam.width)
        self.camera = _free_camera(station, cam)
        self._pool: Any = None
        if self.workers > 1:
            # Start the rendering processes now: they import MuJoCo and make their GL contexts while the run is
            # simulated.
            import multiprocessing

            ctx = multiprocessing.get_context("spawn")  # a fresh GL context per process, nothing inherited
            self._pool = ctx.Pool(self.workers, _init_worker, (os.getpid(), model, self.lookat, cam))

    def _open_writer(self) -> Any:
        """Start ffmpeg on the first frame: a run with no frame in the window leaves no (invalid) video behind."""
        import imageio_ffmpeg

        fmt, cam = self._video_format, self.cam_cfg
        assert fmt is not None and self.video is not None
        self._pending = pending = self._video_out.pending(self.video.suffix.lower())
        try:
            writer = imageio_ffmpeg.write_frames(  # an absolute path: never read as an ffmpeg option
                str(pending.path), (cam.width, cam.height), fps=self.fps, codec=fmt.codec, pix_fmt_out=fmt.pix_fmt,
                quality=fmt.quality, macro_block_size=1, ffmpeg_log_level="error", output_params=list(fmt.params))
            writer.send(None)  # starts ffmpeg
        except Exception as exc:  # a failing ffmpeg raises several types
            raise SimulationError(f"cannot write {printable(self.video)}: {_first_line(exc)}") from None
        return writer

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        t = float(data.time)
        if not self.t_from - 1e-9 <= t <= self.t_to + 1e-9:
            return
        if self.workers > 1:  # rendered in worker processes by render_pending()
            self._states.append((t, data.qpos.copy()))
            return
        self._emit(_draw(self.renderer, data, self.camera, self.cam_cfg))

    def _emit(self, pixels: Any) -> None:
        """Write one frame; a failure discards the output (an existing file or folder stays as it was)."""
        try:
            self._write(pixels)
        except BaseException as exc:
            self.discard()
            if isinstance(exc, Ur3HanoiError) or not isinstance(exc, Exception):
                raise
            where = printable(self.video or self.frames_dir)
            raise SimulationError(f"cannot write {where}: {_first_line(exc)}") from None
        self.count += 1

    def _write(self, pixels: Any) -> None:
        """Append one rendered frame to the video or the frames directory."""
        if self.video is not None:
            if self._writer is None:
                self._writer = self._open_writer()
            self._writer.send(np.ascontiguousarray(pixels))
        else:
            from PIL import Image

            if self._pending is None:
                self._pending = self._frames_out.pending()
            Image.fromarray(pixels).save(self._pending.path / f"frame_{self.count:05d}.png")

    def _finish(self) -> None:
        """Finish the video (ffmpeg) and put the video or the frames in place."""
        pending, self._pending = self._pending, None
        writer, self._writer = self._writer, None
        try:
            if writer is not None:
                writer.close()
        except Exception as exc:
            if pending is not None:
                pending.discard()
            raise SimulationError(f"cannot write {printable(self.video)}: {_first_line(exc)}") from None
        if isinstance(pending, PendingDir):
            pending.commit(replaces=FRAME_NAME)
        elif pending is not None:
            pending.commit()

    def discard(self) -> None:
        """Drop what was rendered: an existing video or frames folder stays as it was."""
        pending, self._pending = self._pending, None
        writer, self._writer = self._writer, None
        if writer is not None:
            with contextlib.suppress(Exception):
                writer.close()
        if pending is not None:
            pending.discard()

    def render_pending(self) -> None:
        """Render the frames recorded for the worker processes, in order, streaming them into the video (ffmpeg
        encodes in its own process meanwhile) or the frames directory; reports progress per frame."""
        states, self._states = self._states, []
        if not states or self._pool is None:
            return
        n = len(states)
        every = max(1, n // 100)
        for i, pixels in enumerate(self._pool.imap(_render_state, states, chunksize=2), start=1):
            self._emit(pixels)
            if self.progress is not None and (i % every == 0 or i == n):
                self.progress(i / n, f"frame {i}/{n}")

    def close(self) -> None:
        """Release the renderer and finish the file; frames recorded for the workers and not yet rendered
        (:meth:`render_pending`) are dropped (an interrupted run)."""
        self._states = []
        if self._pool is not None:
            pool, self._pool = self._pool, None
            pool.terminate()
            pool.join()
        try:
            self.renderer.close()
        finally:
            self._finish()

    def __enter__(self) -> OffscreenRecorder:
        return self

    def __exit__(self, exc_type: object, *exc: object) -> None:
        try:
            if exc_type is not None:
                self.discard()
            else:
                self.render_pending()
        except BaseException:
            self.discard()
            raise
        finally:
            self.close()


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
