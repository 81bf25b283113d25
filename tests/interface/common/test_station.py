"""The transport-neutral station (ur3hanoi.interface.common.station) through the course's station and both bindings,
in process (no ROS, no DDS): a command flood is counted in full while the report, the records and the log lines stay
bounded; the render sink (--frames/--video) writes what the report counts."""

from __future__ import annotations

import gc
import json
import re
import time
from collections.abc import Callable
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from ur3hanoi.interface.common.station import ServerCore, ServerOptions
from ur3hanoi.interface.course.station import CourseStation
from ur3hanoi.interface.ros1.server import RosServer, RosServerOptions
from ur3hanoi.interface.ros2.server import Ros2Server, Ros2ServerOptions

Station = tuple[ServerCore, list[float]]


def _ros1(log: list[str]) -> Station:
    """``ros-station`` and where its arm is (controller convention)."""
    node = RosServer(RosServerOptions(), out=log.append)
    return node, [float(x) for x in node.world.q]


def _ros2(log: list[str]) -> Station:
    """``ros2-station`` (timing honest, so commands execute as sent) and where its arm is (course convention)."""
    node = Ros2Server(Ros2ServerOptions(timing="honest"), out=lambda _s: None, log=log.append)
    return node, node.position()


@pytest.mark.parametrize("make", [_ros1, _ros2], ids=["ros", "ros2"])
def test_the_report_does_not_grow_with_the_number_of_commands(make: Callable[[list[str]], Station]) -> None:
    """1 kHz against 125 Hz (8 commands per period: the lab's re-publish of where the arm is, suction toggled) for
    1600 and 8000 commands: every command counted, the same report size after 5x the commands (it was about 5 kB
    per command), a few log lines however many are refused."""
    sizes, counts = [], []
    for n in (1600, 8000):
        logged: list[str] = []
        node, here = make(logged)
        t0 = time.monotonic()
        for i in range(n):
            node.on_command(SimpleNamespace(destination=here, v=4.0, a=4.0, io_0=bool(i % 2)))
            if i % 8 == 7:
                node.cycle()
        report = node.report()
        sizes.append(len(json.dumps(report, indent=1)))
        counts.append(report["commands"])
        # The refusals' log: the first line at once, then a summary a second of the wall time the commands took
        # (well under a second on an idle machine, more on a loaded one).
        assert len(logged) <= 2 + (time.monotonic() - t0), logged[:5]
    assert [c["executed"] + c["rejected"] + c["queued"] for c in counts] == [1600, 8000]
    assert counts[0]["executed"] > 150 and counts[1]["executed"] > 900 and counts[1]["rejected"] > 6000
    assert report["event_counts"]["suction_on"] + report["event_counts"]["suction_off"] > 100
    assert len(report["executed"]) <= 100 and len(report["rejected"]) <= 100
    assert sizes[1] <= 1.02 * sizes[0], sizes


@pytest.mark.parametrize("kind", ["frames", "video"])
def test_the_render_sink_writes_what_the_report_counts(kind: str, tmp_path: Path,
                                                       monkeypatch: pytest.MonkeyPatch) -> None:
    """ServerCore (the course's station) without a transport, 2 s of real time with one move of joint 1 and
    ``frames`` or ``video``: the rendering process writes as many frames as the report says it rendered (the rest
    dropped, not waited for), the pictures are not blank and show the arm moving. Without a display or MUJOCO_GL,
    the process chooses its OpenGL platform itself (ur3hanoi.opengl), as a script using the library would have it."""
    import imageio_ffmpeg
    from PIL import Image

    from ur3hanoi.opengl import MUJOCO_GL, VERIFIED

    for name in (MUJOCO_GL, VERIFIED, "DISPLAY", "WAYLAND_DISPLAY"):
        monkeypatch.delenv(name, raising=False)
    out = tmp_path / ("run.mp4" if kind == "video" else "frames")
    node = CourseStation(ServerOptions(duration_s=2.0, **{kind: out}), out=lambda _s: None, report_out=lambda _s: None)
    q = [float(x) for x in node.world.q]
    node.on_command(SimpleNamespace(destination=[q[0] + 0.8, *q[1:]], v=3.0, a=6.0, io_0=False))
    try:
        with node.rendering():
            node.loop("ready", lambda: None, lambda: None)
            assert not out.exists()  # written only when the sink closes (ur3hanoi.io.atomic)
    finally:
        gc.unfreeze()
    frames = node.report()["frames"]
    assert frames["rendered"] > 0 and frames["dropped"] >= 0, frames
    if kind == "video":
        assert imageio_ffmpeg.count_frames_and_secs(str(out))[0] == frames["rendered"]
        reader = imageio_ffmpeg.read_frames(str(out))
        meta = next(reader)
        w, h = meta["size"]
        images = [np.frombuffer(f, dtype=np.uint8).reshape(h, w, 3).astype(np.float64) for f in reader]
    else:
        pngs = sorted(out.glob("frame_*.png"))
        assert len(pngs) == frames["rendered"]
        images = []
        for p in pngs:
            with Image.open(p) as im:
                images.append(np.asarray(im.convert("RGB"), dtype=np.float64))
    assert len(images) == frames["rendered"]
    colours = [np.unique(im.astype(np.int64) @ np.array([65536, 256, 1])).size for im in images]
    assert min(im.std() for im in images) > 5.0 and min(colours) > 50, colours
    if len(images) > 1:
        assert max(float(np.abs(im - images[0]).max()) for im in images) > 50.0  # the arm moved
    assert node.report()["frames"] == frames  # closed: the counts are final


def test_a_station_behind_real_time_says_so() -> None:
    """A publish step that stalls the loop 0.45 s once: one warning line naming how far behind it is."""
    logged: list[str] = []
    node = CourseStation(ServerOptions(duration_s=0.6), out=logged.append, report_out=lambda _s: None)
    stalls = iter([0.45])

    def publish() -> None:
        import time

        time.sleep(next(stalls, 0.0))

    node.loop("ready", lambda: None, publish)
    behind = [line for line in logged if "behind real time" in line]
    assert len(behind) == 1 and re.match(r"loop: the station is \d+ ms behind real time: .* lower --rate", behind[0])
