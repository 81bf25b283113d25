"""`ur3hanoi solve --frames/--video` options: --fps, --size, --from/--to, progress on stderr when it is not a
terminal (stdout stays clean), and bad values refused before anything is simulated."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from PIL import Image

from tests.support.opengl_support import without_opengl
from ur3hanoi import cli
from ur3hanoi.opengl import VERIFIED

PROGRESS_LINE = re.compile(r"ur3hanoi solve: +(\d+) % \((move \d+/\d+|done|simulated|frame \d+/\d+)(, (\d+) frames)?\)")
RENDERING_LINE = re.compile(r"ur3hanoi solve: rendering with (the display's OpenGL \(GLFW\)|EGL|OSMesa) \((.*)\)")
"""The first line on stderr of a run that renders: the OpenGL platform (ur3hanoi.opengl) and why."""


def test_frames_in_a_window_at_a_size_and_rate(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    # One block (one move, ~6 s), 5 frames per second, 1.0-2.0 s: frames at 1.0, 1.2, ..., 2.0.
    code = cli.main(["solve", "--start", "1", "--end", "3", "--blocks", "1", "--frames", str(tmp_path),
                     "--size", "32x24", "--fps", "5", "--from", "1", "--to", "2", "--json"])
    captured = capsys.readouterr()
    out = json.loads(captured.out)  # stdout holds the JSON object only
    assert code == 0 and out["status"] == "solved", captured.err
    frames = sorted(tmp_path.glob("frame_*.png"))
    assert len(frames) == 6
    assert {Image.open(f).size for f in frames} == {(32, 24)}
    # Not a terminal, rendering: plain progress lines every 10 %, up to 100 %: simulating, then the frames rendered
    # (in worker processes on a machine with several cores, else during the run, with the frames written so far).
    lines = captured.err.splitlines()
    assert RENDERING_LINE.fullmatch(lines.pop(0)), captured.err
    assert lines and all(PROGRESS_LINE.fullmatch(line) for line in lines), captured.err
    percents = [int(PROGRESS_LINE.fullmatch(line).group(1)) for line in lines]  # type: ignore[union-attr]
    assert percents == sorted(percents) and percents[-1] == 100 and 5 <= len(lines) <= 12
    assert lines[-1].endswith("(frame 6/6)") or lines[-1].endswith("(done, 6 frames)")


def test_progress_lines_on_request_without_rendering(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "2", "--blocks", "1", "--json", "--progress"]) == 0
    captured = capsys.readouterr()
    assert json.loads(captured.out)["status"] == "solved"
    lines = captured.err.splitlines()
    assert lines[-1] == "ur3hanoi solve: 100 % (done)" and all(PROGRESS_LINE.fullmatch(x) for x in lines)


def test_no_progress_by_default_without_a_terminal(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["solve", "--start", "1", "--end", "2", "--blocks", "1", "--json"]) == 0
    assert capsys.readouterr().err == ""


def test_a_video_with_an_unknown_extension_is_refused_up_front(tmp_path: Path,
                                                               capsys: pytest.CaptureFixture[str]) -> None:
    video = tmp_path / "run.avi"
    assert cli.main(["solve", "--start", "1", "--end", "3", "--video", str(video)]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and not video.exists()
    assert captured.err == (f"ur3hanoi: error: cannot write the video {video}: extension '.avi' is not a video "
                            "format ur3hanoi writes: expected one of .mp4, .mkv, .mov, .webm, .gif\n")


@pytest.mark.parametrize(("args", "message"), [
    (["--fps", "10"], "--fps sets how the run is rendered: use with --video FILE or --frames DIR"),
    (["--size", "64x48", "--to", "3"], "--size, --to set how the run is rendered"),
    (["--frames", "F", "--fps", "0"], "argument --fps: '0' is invalid: expected a frame rate [Hz] in [1, 120]"),
    (["--frames", "F", "--fps", "500"], "expected a frame rate [Hz] in [1, 120]"),
    (["--frames", "F", "--size", "640"], "argument --size: '640' is invalid: expected WIDTHxHEIGHT"),
    (["--frames", "F", "--size", "641x480"], "each an even number of pixels in [16, 4096]"),
    (["--frames", "F", "--size", "8x8"], "each an even number of pixels in [16, 4096]"),
    (["--frames", "F", "--from", "-1"], "argument --from: '-1' is invalid: expected a sim time [s]"),
    (["--frames", "F", "--from", "3", "--to", "2"], "--to 2 is invalid: expected a time after --from (3 s)"),
    (["--frames", "F", "--to", "0"], "--to 0 is invalid: expected a time after --from (0 s)"),
    (["--frames", "F", "--from", "1000"], "--from 1000 is invalid: the planned motion lasts"),
], ids=["fps-alone", "size-to-alone", "fps-0", "fps-500", "size-one", "size-odd", "size-small", "from-negative",
        "to-before-from", "to-0", "from-after-end"])
def test_bad_render_options_exit_2_before_rendering(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                    args: list[str], message: str) -> None:
    frames = tmp_path / "frames"
    args = [str(frames) if a == "F" else a for a in args]
    assert cli.main(["solve", "--start", "1", "--end", "3", *args]) == 2
    captured = capsys.readouterr()
    assert message in captured.err and captured.err.count("\n") == 1 and captured.out == ""
    assert not frames.exists() or not any(frames.glob("*.png"))


def test_the_help_lists_the_video_formats_the_recorder_writes() -> None:
    from ur3hanoi.cli.solve import VIDEO_EXTENSIONS
    from ur3hanoi.sim import VIDEO_FORMATS

    assert tuple(VIDEO_FORMATS) == VIDEO_EXTENSIONS


def test_sigterm_while_rendering_stops_every_process_and_keeps_the_old_video(tmp_path: Path) -> None:
    """SIGTERM is a Ctrl-C: the run is discarded, the rendering processes and ffmpeg stopped, no semaphore leaked
    (it ended by the signal's default action, exit -15, and multiprocessing warned of leaked semaphores)."""
    import signal
    import time

    video = tmp_path / "run.mp4"
    video.write_bytes(b"the old video")
    proc = subprocess.Popen([sys.executable, "-m", "ur3hanoi.cli", "solve", "--start", "1", "--end", "3", "--video",
                             str(video)], text=True, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, start_new_session=True)
    try:
        assert proc.stderr is not None
        seen = []
        for line in proc.stderr:  # progress lines: rendering has started once one counts frames
            seen.append(line)
            if "frame" in line:
                break
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=60)
        deadline = time.monotonic() + 2.0
        left = True
        while left and time.monotonic() < deadline:
            left = subprocess.run(["pgrep", "-s", str(proc.pid)], capture_output=True).returncode == 0
            time.sleep(0.05)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    err = "".join(seen) + err
    assert proc.returncode == 143, err
    assert err.splitlines()[-1] == "ur3hanoi solve: terminated (SIGTERM)" and "leaked" not in err, err
    assert video.read_bytes() == b"the old video" and [p.name for p in tmp_path.iterdir()] == ["run.mp4"]
    assert not left, "a process of the run outlived it by 2 s"


def _solve_video(video: Path, prefix: list[str], env: dict[str, str]) -> subprocess.CompletedProcess[str]:
    """A short ``solve --video`` (one block, 2 frames per second, 32x24 px) as a separate command."""
    argv = [*prefix, sys.executable, "-m", "ur3hanoi", "solve", "--start", "1", "--end", "2", "--blocks", "1",
            "--fps", "2", "--size", "32x24", "--video", str(video)]
    return subprocess.run(argv, env=env, cwd=video.parent, capture_output=True, text=True, timeout=300, check=False)


def test_a_video_renders_without_a_display_or_a_setting(tmp_path: Path) -> None:
    """The way CI runs and a student over ssh does: no DISPLAY, no MUJOCO_GL. The command chooses a platform by
    itself, says which, and nothing else reaches stderr but progress (no library warning)."""
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", VERIFIED, "DISPLAY", "WAYLAND_DISPLAY")}
    video = tmp_path / "run.mp4"
    proc = _solve_video(video, [], env)
    assert proc.returncode == 0, proc.stderr
    lines = proc.stderr.splitlines()
    rendering = RENDERING_LINE.fullmatch(lines[0])
    assert rendering and rendering.group(1) in ("EGL", "OSMesa"), proc.stderr
    assert rendering.group(2).startswith("MUJOCO_GL unset, no display"), proc.stderr
    assert all(PROGRESS_LINE.fullmatch(line) for line in lines[1:]), proc.stderr
    wrote = re.search(r"wrote (\d+) frames to ", proc.stdout)
    assert wrote and int(wrote.group(1)) >= 10, proc.stdout  # one move of 5-6 s at 2 Hz
    import imageio_ffmpeg
    import numpy as np

    reader = imageio_ffmpeg.read_frames(str(video))
    w, h = next(reader)["size"]
    frames = [np.frombuffer(f, dtype=np.uint8).reshape(h, w, 3) for f in reader]
    assert len(frames) == int(wrote.group(1)) and (w, h) == (32, 24)
    assert min(float(f.std()) for f in frames) > 5.0  # pictures of the scene, not a blank buffer


def test_with_no_opengl_platform_one_line_exit_2_and_the_old_video_stays(tmp_path: Path) -> None:
    """On a machine without EGL, OSMesa or a display (tests/test_opengl.py checks that the hiding hides): the one
    line naming each platform tried and what provides it, exit 2, before anything is simulated."""
    made = without_opengl()
    if isinstance(made, str):
        pytest.skip(made)
    video = tmp_path / "run.mp4"
    video.write_bytes(b"the old video")
    proc = _solve_video(video, *made)
    assert proc.returncode == 2 and proc.stdout == "", proc.stdout + proc.stderr
    assert proc.stderr.count("\n") == 1, proc.stderr
    assert proc.stderr.startswith("ur3hanoi: error: offscreen rendering found no OpenGL platform that works "
                                  "(MUJOCO_GL unset): tried the display's OpenGL (GLFW): no display"), proc.stderr
    for needs in ("libegl1, libegl-mesa0, libgl1-mesa-dri", "libosmesa6"):
        assert needs in proc.stderr
    assert video.read_bytes() == b"the old video" and [p.name for p in tmp_path.iterdir()] == ["run.mp4"]


def test_a_users_setting_that_fails_is_one_line_and_exit_2(tmp_path: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k not in (VERIFIED, "DISPLAY", "WAYLAND_DISPLAY")}
    env["MUJOCO_GL"] = "glfw"
    video = tmp_path / "run.mp4"
    proc = _solve_video(video, [], env)
    assert proc.returncode == 2 and proc.stdout == "", proc.stderr
    assert proc.stderr == ("ur3hanoi: error: offscreen rendering cannot use MUJOCO_GL='glfw' (set in the environment): "
                           "X11: The DISPLAY environment variable is missing; the display's OpenGL (GLFW) needs a "
                           "display: an X or Wayland session (DISPLAY, WAYLAND_DISPLAY); or unset MUJOCO_GL to let "
                           "ur3hanoi choose\n")
    assert not video.exists()
