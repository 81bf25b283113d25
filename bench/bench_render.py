#!/usr/bin/env python3
"""Benchmark video rendering: `ur3hanoi solve --start 1 --end 3 --video run.mp4` (640x480, 30 frames/s, a 3-block
solve, ~1045 frames) end to end, and where a frame's time goes.

Usage: .venv/bin/python bench/bench_render.py [--no-solve] [--frames N]
Target: <= 40 s wall on two cores without a GPU (goal 25 s), MUJOCO_GL=egl (Mesa llvmpipe).

Reported: the wall time of the command, the CPU time of it and its processes (the rendering workers and ffmpeg
included), CPU / 2 (the wall time two idle cores would need for that work), and the load average around the run:
on a shared machine the wall time measures the neighbours as much as the code. Then the CPU time of one frame
(software GL, one llvmpipe thread, as in a worker) for MuJoCo's default quality and the settings used, and of
encoding one frame with x264's default and "veryfast" presets.
"""

from __future__ import annotations

import argparse
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))


def cpu_children() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def bench_solve(tmp: Path) -> None:
    exe = REPO / ".venv/bin/ur3hanoi"
    out = tmp / "run.mp4"
    cmd = [str(exe) if exe.exists() else "ur3hanoi", "solve", "--start", "1", "--end", "3", "--video", str(out)]
    load0 = os.getloadavg()[0]
    c0, t0 = cpu_children(), time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, env={**os.environ, "MUJOCO_GL": "egl"}, check=False)
    wall, cpu = time.perf_counter() - t0, cpu_children() - c0
    load1 = os.getloadavg()[0]
    if proc.returncode != 0:
        raise SystemExit(f"solve failed: {proc.stderr.strip()}")
    frames = next((line.split()[1] for line in proc.stdout.splitlines() if "wrote" in line), "?")
    print(f"solve --video 640x480 30 fps: {frames} frames in {wall:.1f} s wall; CPU {cpu:.1f} s (CPU / 2 cores = "
          f"{cpu / 2:.1f} s); {os.cpu_count()} cores, load average {load0:.1f} before, {load1:.1f} after; "
          f"{out.stat().st_size / 1e6:.1f} MB")


def bench_frame(n: int) -> None:
    os.environ["MUJOCO_GL"] = "egl"
    os.environ["LP_NUM_THREADS"] = "1"  # as in a rendering worker
    import mujoco
    import numpy as np

    from ur3hanoi.sim import build_task_scene
    from ur3hanoi.sim.render import CameraConfig, _draw, _free_camera, _set_quality
    from ur3hanoi.station.calibration import load_station

    def cpu_self() -> float:
        r = resource.getrusage(resource.RUSAGE_SELF)
        return r.ru_utime + r.ru_stime

    st = load_station("lab_sim")
    scene = build_task_scene(st, 0, 3)
    px = None
    for label, cam in (("MuJoCo default (shadow map 4096, MSAA 4, reflections)",
                        CameraConfig(shadow_size=4096, multisamples=4, reflections=True)),
                       ("no reflections", CameraConfig(shadow_size=4096, multisamples=4, reflections=False)),
                       ("no reflections, no MSAA", CameraConfig(shadow_size=4096, multisamples=0)),
                       ("used: shadow map 1024, no MSAA, no reflections", CameraConfig()),
                       ("no shadows", CameraConfig(shadow_size=0))):
        _set_quality(scene.model, cam)
        r = mujoco.Renderer(scene.model, cam.height, cam.width)
        camera = _free_camera(st, cam)
        _draw(r, scene.data, camera, cam)
        c0, t0 = cpu_self(), time.perf_counter()
        for _ in range(n):
            px = _draw(r, scene.data, camera, cam)
        cpu, wall = (cpu_self() - c0) / n, (time.perf_counter() - t0) / n
        print(f"  frame, {label}: CPU {1e3 * cpu:.1f} ms (wall {1e3 * wall:.1f} ms)")
        r.close()
    import imageio_ffmpeg

    assert px is not None
    for preset in ("medium", "veryfast"):
        c0 = cpu_children()
        w = imageio_ffmpeg.write_frames(os.devnull, (640, 480), fps=30, codec="libx264", quality=7, macro_block_size=1,
                                        ffmpeg_log_level="error", output_params=["-preset", preset, "-f", "mp4"])
        w.send(None)
        for i in range(4 * n):
            w.send(np.ascontiguousarray(np.roll(px, i, axis=1)))
        w.close()
        print(f"  encode, x264 preset {preset}: CPU {1e3 * (cpu_children() - c0) / (4 * n):.1f} ms a frame")


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--no-solve", action="store_true", help="only the per-frame costs")
    ap.add_argument("--frames", type=int, default=20, help="frames per per-frame measurement")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        if not args.no_solve:
            bench_solve(Path(tmp))
    bench_frame(args.frames)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
