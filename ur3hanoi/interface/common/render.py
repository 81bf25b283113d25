"""Offscreen rendering for a station's ``--frames``/``--video`` (``ros-station``, ``ros2-station``) in a separate,
low-priority process.

Software EGL renders a 640x480 frame in about 100 ms and holds the interpreter while doing so: inside the control
process it would stall the 8 ms loop (measured: 200 ms lags). So a child process (``spawn``, niced, Mesa's
llvmpipe limited to one thread) builds the same task scene and renders the joint state it is sent with
:class:`ur3hanoi.sim.OffscreenRecorder`; while it is busy, offered states are dropped. A video therefore has the
frames the machine could render (a few per second with software GL) and plays faster than real time; the control
loop keeps real time.

The child ignores SIGINT (a Ctrl-C reaches the whole foreground group: the station, not the child, decides when the
video ends) and stops on SIGTERM or when the station dies (``PR_SET_PDEATHSIG``, or the end of file of its pipe):
then it discards what it rendered, so an existing video or frames folder stays as it was
(:func:`ur3hanoi.lifecycle.child_start`).
"""

from __future__ import annotations

import multiprocessing
import os
import signal
from multiprocessing.connection import Connection
from pathlib import Path
from typing import Any

from ur3hanoi.arrays import FloatArray
from ur3hanoi.errors import InputError, SimulationError


class _StoppedError(Exception):
    """SIGTERM, or the station died: discard the output and exit."""


def _stopped(_signum: int, _frame: object) -> None:
    raise _StoppedError


def _worker(parent: int, conn: Connection, calibration: str, n_blocks: int, frames: Path | None,
            video: Path | None) -> None:
    from ur3hanoi.lifecycle import child_start

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the station stops us (a Ctrl-C must not cut the video short)
    child_start(parent)  # SIGTERM at its default until the recorder exists: nothing to discard before
    os.environ.setdefault("LP_NUM_THREADS", "1")  # llvmpipe: leave the other core to the control loop
    os.nice(10)
    try:
        from ur3hanoi.opengl import use_platform

        use_platform()  # the station's command chose it (MUJOCO_GL, inherited): nothing to try again
        import mujoco

        from ur3hanoi.sim import OffscreenRecorder, build_task_scene
        from ur3hanoi.station.calibration import load_station

        station = load_station(calibration)
        scene = build_task_scene(station, 0, n_blocks)
        recorder = OffscreenRecorder(station, scene.model, frames_dir=frames, video=video)
    except Exception as exc:  # reported to the station, which raises it as one line
        conn.send(f"error: {' '.join(str(exc).split())}")
        return
    signal.signal(signal.SIGTERM, _stopped)
    try:
        conn.send(f"ready {recorder.fps}")
        while True:
            qpos = conn.recv()
            if qpos is None:
                break
            scene.data.qpos[:] = qpos
            mujoco.mj_forward(scene.model, scene.data)
            recorder(scene.model, scene.data)
            conn.send(recorder.count)
    except BaseException as exc:  # no half-written output, whatever stopped the loop
        recorder.discard()
        recorder.close()
        if isinstance(exc, _StoppedError | EOFError | OSError):
            return  # SIGTERM, or the station is gone
        raise
    recorder.close()
    conn.send("closed")


class FrameProcess:
    """The rendering child process (see the module docstring). Use :meth:`offer` each frame period, then
    :meth:`close`.

    Raises:
        SimulationError: the child could not set up rendering (its error, one line).
    """

    def __init__(self, calibration: str, n_blocks: int, frames: Path | None, video: Path | None,
                 start_timeout_s: float = 120.0) -> None:
        ctx = multiprocessing.get_context("spawn")  # never fork a process that runs rospy's or DDS threads
        self._conn, child = ctx.Pipe()
        self._proc: Any = ctx.Process(target=_worker, args=(os.getpid(), child, calibration, n_blocks, frames, video),
                                      daemon=True, name="ur3hanoi-render")
        self._proc.start()
        child.close()
        self._busy = False
        self.offered = 0
        self.dropped = 0
        self.rendered = 0
        if not self._conn.poll(start_timeout_s):
            self._kill()
            raise SimulationError(f"the rendering process did not start within {start_timeout_s:g} s")
        hello = self._conn.recv()
        if not str(hello).startswith("ready"):
            self._kill()
            raise SimulationError(f"the rendering process could not start: {str(hello).removeprefix('error: ')}")
        self.fps = float(str(hello).split()[1])

    def _collect(self) -> None:
        while self._busy and self._conn.poll():
            reply = self._conn.recv()
            if isinstance(reply, int):
                self.rendered = reply
                self._busy = False

    def offer(self, qpos: FloatArray) -> None:
        """Send the state to render unless the child is still busy with the last one (then it is dropped)."""
        self._collect()
        if self._busy:
            self.dropped += 1
            return
        self._conn.send(qpos.copy())
        self._busy = True
        self.offered += 1

    def close(self, timeout_s: float = 60.0) -> dict[str, int]:
        """Finish the file (waits for the frame in progress) and stop the child; returns the frame counts."""
        if self._proc.is_alive():
            if self._busy and self._conn.poll(timeout_s):
                self._collect()
            try:
                self._conn.send(None)
                while self._conn.poll(timeout_s) and self._conn.recv() != "closed":
                    pass
            except (OSError, EOFError):
                pass
            self._proc.join(timeout_s)
        self._kill()
        return {"rendered": self.rendered, "dropped": self.dropped}

    def _kill(self) -> None:
        if self._proc.is_alive():
            self._proc.kill()
            self._proc.join(10)


class FrameOutput:
    """A server's ``--frames``/``--video``: the rendering process (:class:`FrameProcess`, started by :meth:`open`
    before the transport starts threads, so a slow start cannot delay messages), offered the joint state once per
    frame period of world time, and its counts (final once :meth:`close` d)."""

    def __init__(self, calibration: str, n_blocks: int, frames: Path | None, video: Path | None) -> None:
        if frames is not None and video is not None:
            raise InputError("give at most one of frames (a PNG folder) and video (an MP4 file)")
        self.calibration, self.n_blocks, self.frames, self.video = calibration, n_blocks, frames, video
        self._process: FrameProcess | None = None
        self._final: dict[str, int] | None = None
        self._next_frame_s = 0.0  # world time of the next frame [s]

    def open(self, world_time_s: float) -> None:
        """Start the rendering process (nothing without an output, or when it runs already)."""
        if self._process is not None or (self.frames is None and self.video is None):
            return
        self._process = FrameProcess(self.calibration, self.n_blocks, self.frames, self.video)
        self._next_frame_s = world_time_s

    def close(self) -> None:
        """Finish the PNG folder or video and stop the process; nothing when not rendering or already closed."""
        if self._process is not None and self._final is None:
            self._final = self._process.close()

    def offer(self, world_time_s: float, qpos: FloatArray) -> None:
        """Send the joint state when a frame period of world time has passed."""
        process = self._process
        if process is None or self._final is not None or world_time_s + 1e-9 < self._next_frame_s:
            return
        process.offer(qpos)
        self._next_frame_s += 1.0 / process.fps

    def counts(self) -> dict[str, int] | None:
        """``{"rendered": n, "dropped": n}`` (None when not rendering)."""
        if self._final is not None:
            return self._final
        return None if self._process is None else {"rendered": self._process.rendered,
                                                   "dropped": self._process.dropped}
