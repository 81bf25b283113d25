"""`ur3hanoi solve --frames/--video` options: --fps, --size, --from/--to, progress on stderr when it is not a
terminal (stdout stays clean), and bad values refused before anything is simulated."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from PIL import Image

from ur3hanoi import cli

PROGRESS_LINE = re.compile(r"ur3hanoi solve: +(\d+) % \((move \d+/\d+|done|simulated|frame \d+/\d+)(, (\d+) frames)?\)")


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
    import os
    import signal
    import subprocess
    import sys
    import time

    video = tmp_path / "run.mp4"
    video.write_bytes(b"the old video")
    env = dict(os.environ, MUJOCO_GL=os.environ.get("MUJOCO_GL", "egl"))
    proc = subprocess.Popen([sys.executable, "-m", "ur3hanoi.cli", "solve", "--start", "1", "--end", "3", "--video",
                             str(video)], env=env, text=True, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
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
