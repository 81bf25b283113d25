"""The replay page (ur3hanoi.replay): recorded poses, the overlay's timeline, a self-contained file, and the page
itself opened in Debian's headless chromium with the network off (screenshots read pixel by pixel)."""

from __future__ import annotations

import colorsys
import json
import math
import re
import subprocess
from functools import cache
from pathlib import Path

import mujoco
import numpy as np
import pytest
from PIL import Image

from tests.support.browser_support import chromium, offline_prefix
from tests.support.sim_helpers import STATIONS, planned
from ur3hanoi.errors import SuctionFaultError
from ur3hanoi.replay import PoseRecorder, SinkTee, page_html, record_plan, write_plan_replay, write_run_replay
from ur3hanoi.replay.timeline import FAULT_KINDS, timeline_of_plan
from ur3hanoi.sim import Faults, build_task_scene, run_plan
from ur3hanoi.sim.result import SimResult
from ur3hanoi.sim.scene import BLOCK_RGBA, slot_centers

DROP_MOVE = 3  # 0-based: the green block falls during move 4's carry


@cache
def dropped_run() -> tuple[SimResult, PoseRecorder, object]:
    """A 3-block solve on lab_sim whose 4th move loses its block (halts), recorded at 30 frames/s."""
    plan = planned("lab_sim", 0, 2)
    scene = build_task_scene(STATIONS["lab_sim"], 0, 3)
    rec = PoseRecorder(scene.model)
    with pytest.raises(SuctionFaultError) as info:
        run_plan(plan, Faults(drop_during_move=DROP_MOVE), frames=rec, scene=scene)
    assert info.value.result is not None
    return info.value.result, rec, scene


# ------------------------------------------------------------------------------------------------ recording


def test_record_plan_carries_each_block_from_its_source_to_its_destination_slot() -> None:
    plan = planned("lab_sim", 0, 2)
    st = STATIONS["lab_sim"]
    scene = build_task_scene(st, 0, 3)
    track = record_plan(plan, scene, fps=10.0)
    assert track.t[0] == 0.0 and track.t[-1] == pytest.approx(plan.trajectory.t[-1], abs=0.1)
    centers = slot_centers(st)
    block_geom = {b: scene.model.body_geomadr[scene.block_body[b]] for b in scene.block_body}
    col = {b: int(np.flatnonzero(track.geoms == g)[0]) for b, g in block_geom.items()}
    for b, i in col.items():
        # Starts in its start slot (block 0 at the bottom of tower 1) and ends stacked on tower 3.
        np.testing.assert_allclose(track.pos[0, i], centers[0, b], atol=1e-6)
        np.testing.assert_allclose(track.pos[-1, i], centers[2, b], atol=3e-3)
    # While carried, a block keeps its offset to the suction site in the cup's frame (fixed to the cup).
    tr = plan.trajectory
    k = np.minimum(np.rint(track.t * tr.rate_hz).astype(int), len(tr.t) - 1)
    carrying = tr.suction[k] & (tr.move_index[k] == 0)
    assert carrying.sum() > 10
    first = plan.moves[0].block
    d = scene.data
    offsets = []
    for f in np.flatnonzero(carrying):
        d.qpos[scene.arm_qadr] = tr.q[k[f]]
        mujoco.mj_kinematics(scene.model, d)
        R = d.site_xmat[scene.site_id].reshape(3, 3)
        offsets.append(R.T @ (track.pos[f, col[first]] - d.site_xpos[scene.site_id]))
    np.testing.assert_allclose(offsets, np.repeat(offsets[:1], len(offsets), axis=0), atol=1e-6)


class _Counter:
    def __init__(self, fps: float) -> None:
        self.fps, self.times = fps, []

    def __call__(self, model: mujoco.MjModel, data: mujoco.MjData) -> None:
        self.times.append(float(data.time))


def test_sink_tee_gives_each_sink_its_own_frame_rate() -> None:
    fast, slow = _Counter(30.0), _Counter(7.5)
    tee = SinkTee([fast, slow])
    assert tee.fps == 30.0
    data = mujoco.MjData(mujoco.MjModel.from_xml_string("<mujoco/>"))
    for i in range(91):  # the executor calls at tee.fps: 0 .. 3 s
        data.time = i / 30.0
        tee(None, data)  # type: ignore[arg-type]
    np.testing.assert_allclose(fast.times, np.arange(91) / 30.0, atol=1e-12)
    np.testing.assert_allclose(slow.times, np.arange(0.0, 3.0 + 1e-9, 1 / 7.5), atol=1 / 30.0 + 1e-9)
    assert len(slow.times) == 23


# ------------------------------------------------------------------------------------------------ timeline


def test_run_timeline_names_the_halt_and_stops_counting_moves() -> None:
    result, rec, _ = dropped_run()
    plan = planned("lab_sim", 0, 2)
    from ur3hanoi.replay import timeline_of_run

    tl = timeline_of_run(plan, result, rec.track().t, "t")
    drops = [e.t for e in result.feedback_events if e.kind == "dropped"]
    assert tl.fault_t == pytest.approx(min(drops), abs=1e-9)
    assert tl.fault_message is not None and "move 4/7" in tl.fault_message and tl.fault_move == DROP_MOVE
    before, after = tl.t < tl.fault_t, tl.t >= tl.fault_t
    assert set(tl.move[before].tolist()) == {0, 1, 2, 3}
    assert set(tl.move[after].tolist()) == {-1}
    # Suction: on while carrying in move 1; off at the end (the halt vents it); held only while on.
    assert not tl.suction[-1] and not tl.held[-1]
    assert not np.any(tl.held & ~tl.suction)
    carrying_move1 = tl.held & (tl.move == 0)
    assert carrying_move1.sum() > 30  # a carry lasts seconds at 30 frames/s


def test_plan_timeline_follows_the_plan() -> None:
    plan = planned("lab_sim", 0, 2)
    t = np.arange(0.0, plan.trajectory.t[-1], 0.5)
    tl = timeline_of_plan(plan, t, "t")
    k = np.rint(t * plan.trajectory.rate_hz).astype(int)
    np.testing.assert_array_equal(tl.move, plan.trajectory.move_index[k])
    np.testing.assert_array_equal(tl.suction, plan.trajectory.suction[k])
    assert tl.fault_t is None and len(tl.moves) == 7 and tl.moves[0].startswith("block 3 (red): tower 1 height 3")


# ------------------------------------------------------------------------------------------------ the file


def test_page_is_self_contained_and_small(tmp_path: Path) -> None:
    result, rec, scene = dropped_run()
    out = tmp_path / "replay.html"
    size = write_run_replay(out, planned("lab_sim", 0, 2), scene, rec, result, "drop </script> test")  # type: ignore[arg-type]
    text = out.read_text(encoding="utf-8")
    assert size == len(text.encode()) and size < 15e6
    # Nothing is fetched: no external script, stylesheet, image or frame; no URL but data: ones in attributes.
    assert not re.search(r"<(script|link|img|iframe)[^>]+(src|href)\s*=", text, re.I)
    assert "</script> test" not in text  # a title cannot close the script element
    m = re.search(r"var UR3_TIMELINE = (\{.*?\});\n", text)
    assert m is not None
    data = json.loads(m.group(1))
    assert data["fault"]["t"] == pytest.approx(min(e.t for e in result.feedback_events if e.kind == "dropped"),
                                               abs=1e-4)
    assert len(data["t"]) == len(data["move"]) == rec.count


def test_page_html_escapes_the_title() -> None:
    plan = planned("lab_sim", 0, 2)
    tl = timeline_of_plan(plan, np.array([0.0, 1.0]), "a<b")
    assert "<title>a&lt;b</title>" in page_html([], tl, "a<b")


# ------------------------------------------------------------------------------------------------ in a browser


def _browse(url: str, tmp: Path, name: str, mode: str) -> subprocess.CompletedProcess[str]:
    """Open ``url`` in headless chromium with the network off: ``mode`` "screenshot" (800x600 PNG at
    tmp/name.png) or "dump" (the DOM after load, on stdout)."""
    args = [*offline_prefix(), chromium(), "--headless", "--no-sandbox", "--use-angle=swiftshader",
            "--enable-unsafe-swiftshader", "--no-first-run", f"--user-data-dir={tmp / ('profile-' + name)}",
            "--window-size=800,600", "--hide-scrollbars"]
    args += [f"--screenshot={tmp / (name + '.png')}"] if mode == "screenshot" else ["--dump-dom"]
    return subprocess.run([*args, url], capture_output=True, text=True, timeout=120)


SCENE_ROWS = slice(175, 545)
"""Rows of the 800x600 screenshot below the info box and above the timeline bar: the 3-D view only."""


def _mask(img: np.ndarray, rgba: tuple[float, float, float, float]) -> np.ndarray:
    """Pixels of a block's colour under the viewer's lighting: its hue within 12 deg, saturated (the brown table,
    hue 28 deg, has saturation 0.5; the blocks 0.85-0.9) and not dark."""
    hsv = np.asarray(Image.fromarray(img).convert("HSV")).astype(float)
    r, g, b = rgba[:3]
    hue_ref = 360.0 * colorsys.rgb_to_hsv(r, g, b)[0]
    hue = hsv[..., 0] * 360.0 / 255.0
    dh = np.abs((hue - hue_ref + 180.0) % 360.0 - 180.0)
    return (dh < 12.0) & (hsv[..., 1] > 0.7 * 255) & (hsv[..., 2] > 0.25 * 255)


def _end_of_move_3() -> float:
    """A moment [s] at the end of move 3 (red tower 3 -> 2 placed, the arm back above it), read off the plan to
    the 0.01 s the address gives, so the test follows the planner's timing."""
    tr = planned("lab_sim", 0, 2).trajectory
    last = int(np.flatnonzero(tr.move_index == 2)[-1])
    return math.floor((float(tr.t[last]) - 0.05) * 100.0) / 100.0


@pytest.fixture(scope="module")
def browser_shots(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[float, np.ndarray], Path, float]:
    tmp = tmp_path_factory.mktemp("replay")
    result, rec, scene = dropped_run()
    page = tmp / "replay.html"
    write_run_replay(page, planned("lab_sim", 0, 2), scene, rec, result, "drop test")  # type: ignore[arg-type]
    shots = {}
    t_mid = _end_of_move_3()
    for t in (0.0, t_mid):
        name = f"t{t:g}"
        proc = _browse(f"{page.as_uri()}#t={t:g}", tmp, name, "screenshot")
        assert proc.returncode == 0, proc.stderr[-2000:]
        shots[t] = np.asarray(Image.open(tmp / f"{name}.png").convert("RGB"))[SCENE_ROWS]
    halted = [e.t for e in result.feedback_events if e.kind in FAULT_KINDS]
    return shots, page, float(min(halted))


def test_browser_draws_the_arm_and_the_blocks_and_they_move(browser_shots) -> None:  # type: ignore[no-untyped-def]
    shots, _, _ = browser_shots
    a, b = shots[0.0], shots[_end_of_move_3()]
    assert a.shape == b.shape == (370, 800, 3)
    centroids = {}
    for colour in ("green", "yellow", "red"):
        ma, mb = _mask(a, BLOCK_RGBA[colour]), _mask(b, BLOCK_RGBA[colour])
        assert ma.sum() > 40 and mb.sum() > 40, f"{colour} block not drawn: {ma.sum()} / {mb.sum()} px"
        centroids[colour] = (np.argwhere(ma).mean(axis=0), np.argwhere(mb).mean(axis=0))
    # At the end of move 3 (before the drop): red went tower 1 -> 2, yellow tower 1 -> 3, green stayed.
    moved = {c: float(np.linalg.norm(p1 - p0)) for c, (p0, p1) in centroids.items()}
    assert moved["red"] > 20 and moved["yellow"] > 20 and moved["green"] < 3, moved
    # The arm: the UR3's grey (0.7 under light: unsaturated mid-to-light grey) fills a large area, and moves.
    def grey(img: np.ndarray) -> np.ndarray:
        f = img.astype(int)
        return (f.max(axis=-1) - f.min(axis=-1) < 12) & (f.mean(axis=-1) > 90) & (f.mean(axis=-1) < 235)

    ga, gb = grey(a), grey(b)
    assert ga.sum() > 3000 and gb.sum() > 3000
    assert (ga ^ gb).sum() > 1500  # the arm is elsewhere


def test_browser_overlay_shows_the_moment_named_in_the_address(browser_shots, tmp_path: Path) -> None:  # type: ignore[no-untyped-def]
    _, page, t_fault = browser_shots
    t_mid = _end_of_move_3()
    proc = _browse(f"{page.as_uri()}#t={t_mid:.2f}", tmp_path, "dom", "dump")
    assert proc.returncode == 0, proc.stderr[-2000:]
    dom = proc.stdout
    assert re.search(rf'id="ur3-time">{t_mid:.2f} s / \d+\.\d\d s<', dom)
    assert 'id="ur3-move">move 3/7: block 3 (red): tower 3 height 1 -&gt; tower 2 height 2<' in dom
    assert re.search(rf'id="ur3-fault"[^>]*>halted at {t_fault:.2f} s: suction fault in move 4/7', dom)
    assert 'id="ur3-play">Play<' in dom  # opened paused at the named moment
    after = _browse(f"{page.as_uri()}#t={t_fault + 0.2:.2f}", tmp_path, "dom18", "dump").stdout
    assert 'id="ur3-move">halted in move 4/7: the arm stops' in after


def test_plan_replay_writes_a_page(tmp_path: Path) -> None:
    plan = planned("lab_sim", 0, 2)
    out = tmp_path / "plan.html"
    size = write_plan_replay(out, plan, build_task_scene(STATIONS["lab_sim"], 0, 3), "plan")
    assert out.stat().st_size == size < 15e6


# ------------------------------------------------------------------------------------------------ the commands


def test_cli_solve_and_plan_write_a_page(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from ur3hanoi.cli import main

    assert main(["solve", "--start", "1", "--end", "2", "--blocks", "1", "--html", str(tmp_path / "s.html")]) == 0
    assert "wrote the replay page" in capsys.readouterr().out
    assert main(["solve", "--start", "1", "--end", "2", "--blocks", "2", "--remove-block", "1",
                 "--html", str(tmp_path / "f.html")]) == 3
    text = (tmp_path / "f.html").read_text()
    data = json.loads(re.search(r"var UR3_TIMELINE = (\{.*?\});\n", text).group(1))  # type: ignore[union-attr]
    assert data["fault"]["move"] == 2 and "is missing" in data["fault"]["message"]  # block 1 is picked in move 2
    assert main(["plan", "--start", "1", "--end", "2", "--blocks", "1", "--no-collision",
                 "--html", str(tmp_path / "p.html")]) == 0
    assert (tmp_path / "p.html").stat().st_size > 1e6


def test_cli_html_without_meshcat_names_the_extra(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    import sys

    from ur3hanoi.cli import main

    monkeypatch.setitem(sys.modules, "meshcat", None)
    assert main(["plan", "--start", "1", "--end", "3", "--html", str(tmp_path / "p.html")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["ur3hanoi: error: --html needs meshcat (its three.js viewer), which is not installed: pip install "
                   "'ur3hanoi[replay]'"]
    assert not (tmp_path / "p.html").exists()


def test_the_same_plan_gives_the_same_page(tmp_path: Path) -> None:
    plan = planned("lab_sim", 0, 2)
    pages = []
    for i in range(2):
        out = tmp_path / f"p{i}.html"
        write_plan_replay(out, plan, build_task_scene(STATIONS["lab_sim"], 0, 3), "plan", fps=5.0)
        pages.append(out.read_bytes())
    assert pages[0] == pages[1]
