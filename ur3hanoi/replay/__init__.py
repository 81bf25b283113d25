"""The replay page: a run (or a plan) as one self-contained, offline HTML file with the UR3, the blocks and the
towers in 3-D, a timeline to play, pause and scrub, the move and the suction state at each moment, and on a fault
the moment of the halt and its message. ``replay.html#t=12.5`` opens at 12.5 s of the run.

Modules, in order of dependency: :mod:`~ur3hanoi.replay.recorder` (poses of the drawn geoms at a frame rate, from
a simulated run or a plan), :mod:`~ur3hanoi.replay.timeline` (the overlay's data), :mod:`~ur3hanoi.replay.scene`
(meshcat commands: meshes, materials, camera, animation), :mod:`~ur3hanoi.replay.page` (the HTML file).

Why meshcat. The two maintained libraries that write a self-contained 3-D page from Python are meshcat and viser:

- **meshcat** (0.3.2, already installed: placo depends on it) ships its three.js viewer as one bundled
  ``main.min.js`` (about 0.85 MB) and scene commands as msgpack, the format of its own static export
  (``Visualizer.static_html()``, which needs meshcat's ZeroMQ server running; the page is built here from the same
  commands without a server). Its player has play/pause/reset and a time slider (three.js ``AnimationMixer``
  clips per object) but no overlay, no start time from the address, and on reaching the end it rewinds to 0; the
  page therefore drives the player's ``seek`` from a small overlay script instead of its clock.
- **viser** (1.x) records scenes to a ``.viser`` file played back by its client build, a folder of JavaScript
  files served over HTTP: an embedded single file is not a supported output, and it would add viser, its
  websockets server and the client build to the dependencies.

A 3-block solve's page is about 3 MB (the viewer 0.85 MB, the UR3's seven meshes as MuJoCo compiled them about
1.3 MB as base64, the animation at 30 frames/s with keyframes of resting objects left out); opened from disk, no
network, no server.
"""

from __future__ import annotations

from pathlib import Path

from ur3hanoi.plan.types import Plan
from ur3hanoi.replay.page import page_html, write_page
from ur3hanoi.replay.recorder import PoseRecorder, PoseTrack, SinkTee, drawn_geoms, record_plan
from ur3hanoi.replay.scene import scene_commands
from ur3hanoi.replay.timeline import Timeline, timeline_of_plan, timeline_of_run
from ur3hanoi.sim.result import SimResult
from ur3hanoi.sim.scene import TaskScene

REPLAY_FPS = 30.0
"""Frames per second of sim time the replay samples (three.js interpolates between them)."""


def write_run_replay(path: str | Path, plan: Plan, scene: TaskScene, recorder: PoseRecorder, result: SimResult,
                     title: str, inputs: tuple[Path, ...] = ()) -> int:
    """Write the replay of a simulated run (``recorder`` was its frame sink); returns the page's size [bytes]."""
    track = recorder.track()
    timeline = timeline_of_run(plan, result, track.t, title)
    return write_page(path, scene_commands(scene.model, scene.station, track), timeline, title, inputs)


def write_plan_replay(path: str | Path, plan: Plan, scene: TaskScene, title: str, inputs: tuple[Path, ...] = (),
                      fps: float = REPLAY_FPS) -> int:
    """Write the replay of a plan posed without physics (:func:`record_plan`); returns the page's size [bytes]."""
    track = record_plan(plan, scene, fps)
    timeline = timeline_of_plan(plan, track.t, title)
    return write_page(path, scene_commands(scene.model, scene.station, track), timeline, title, inputs)


__all__ = [
    "REPLAY_FPS",
    "PoseRecorder",
    "PoseTrack",
    "SinkTee",
    "Timeline",
    "drawn_geoms",
    "page_html",
    "record_plan",
    "scene_commands",
    "timeline_of_plan",
    "timeline_of_run",
    "write_page",
    "write_plan_replay",
    "write_run_replay",
]
