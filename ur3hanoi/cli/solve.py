"""``ur3hanoi solve``: run the lab in MuJoCo (plan, execute with suction feedback, verify).

With ``--table FILE --key KEY`` the arm follows that table's waypoints (:func:`ur3hanoi.plan.plan_table`) instead
of the ones ur3hanoi generates from the calibration. The scene is the calibration's: ``--key sim_pos`` defaults to
the shipped ``lab_sim`` (the course's Gazebo world, which ``sim_pos`` tables are recorded in); ``--key real_pos``
requires ``--calibration`` (a real station's table fits only that station's geometry).

Rendering (``--video``/``--frames``) takes ``--fps``, ``--size WxH`` and a sim-time window ``--from``/``--to``.
Progress goes to stderr: a bar on a terminal; plain lines every 10 % when stderr is not a terminal and the run
renders, or with ``--progress``. Standard output carries only the result (one JSON object with ``--json``).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any, NamedTuple

from ur3hanoi.cli import exit_codes
from ur3hanoi.cli.common import (
    DEFAULT_CALIBRATION,
    add_suction_profile_option,
    calibration_ref,
    check_render_outputs,
    input_file,
    require_replay,
    shown,
)
from ur3hanoi.cli.options import (
    BLOCKS,
    FPS,
    SEED,
    SIM_TIME,
    SPEED,
    TABLE_KEYS,
    UsageError,
    check_blocks,
    check_faults,
    check_plan_size,
    check_window,
    image_size,
    option,
    station_number,
)
from ur3hanoi.cli.progress import phases, progress_sink
from ur3hanoi.cli.prompt import towers
from ur3hanoi.errors import SuctionFaultError, Ur3HanoiError

if TYPE_CHECKING:
    from ur3hanoi.opengl import Choice
    from ur3hanoi.plan import Plan
    from ur3hanoi.sim import ProgressFn, SimResult, TaskScene
    from ur3hanoi.station.calibration import Station

VIDEO_EXTENSIONS = (".mp4", ".mkv", ".mov", ".webm", ".gif")
"""The video extensions, for the help text (kept equal to ``ur3hanoi.sim.VIDEO_FORMATS``, which is not imported
here: building the parser must not load MuJoCo)."""

def add(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("solve", help="run the lab in MuJoCo: plan, execute with suction feedback, verify",
                       description="Solve the Tower of Hanoi in a MuJoCo simulation of the station: the UR3 "
                                   "follows the planned trajectory, the suction cup grasps by weld, and the "
                                   "program halts like the lab's (suction off, arm home, exit 3) when a block is "
                                   "missing or dropped. Towers, heights and moves are numbered from 1. Without "
                                   "--start/--end it prompts on a terminal like the lab program.")
    p.add_argument("--start", type=station_number("a tower number"), metavar="S",
                   help="start tower (1-based, 1..the station's towers)")
    p.add_argument("--end", type=station_number("a tower number"), metavar="E",
                   help="destination tower (1-based, 1..the station's towers)")
    p.add_argument("--blocks", type=option(BLOCKS), default=None, metavar="N",
                   help=f"{BLOCKS.expected()} (default: the grid's heights, 3 on the lab)")
    p.add_argument("--calibration", default=None, metavar="CAL",
                   help=f"station calibration YAML, or a shipped station name (default {DEFAULT_CALIBRATION}; "
                        "required with --key real_pos)")
    p.add_argument("--table", metavar="FILE",
                   help="follow the waypoints of this lab-format table (lab2_data.yaml) instead of generated ones: "
                        "joint moves between its entries like the lab program; a missed block halts (exit 3) "
                        "naming the table entry")
    p.add_argument("--key", choices=TABLE_KEYS, help="the table key to follow (with --table)")
    p.add_argument("--remove-block", type=station_number("a height"), metavar="H",
                   help="fault injection: spawn without the block at height H (1-based), like lab2_spawn.py")
    p.add_argument("--drop-during-move", type=station_number("a move number"), metavar="M",
                   help="fault injection: the suction loses its block in the middle of move M's carry (1-based)")
    p.add_argument("--speed", type=option(SPEED), default=1.0, metavar="F",
                   help=f"fraction of the joint speed/acceleration/jerk limits, in [{SPEED.lo:g}, {SPEED.hi:g}] "
                        "(default 1)")
    p.add_argument("--seed", type=option(SEED), default=0, metavar="K",
                   help=f"seed of the suction feedback noise, an integer in [0, {SEED.hi}]")
    out = p.add_mutually_exclusive_group()
    out.add_argument("--video", metavar="FILE",
                     help=f"render a video offscreen, by extension {', '.join(VIDEO_EXTENSIONS)} (needs "
                          "imageio-ffmpeg; OpenGL: the display's, else EGL, else OSMesa, or MUJOCO_GL)")
    out.add_argument("--frames", metavar="DIR", help="render PNG frames offscreen into DIR (OpenGL as --video)")
    p.add_argument("--fps", type=option(FPS), default=None, metavar="HZ",
                   help=f"frames per second of sim time, {FPS.expected()} (default 30)")
    p.add_argument("--size", type=image_size, default=None, metavar="WxH",
                   help="image size in pixels, even numbers in [16, 4096] (default 640x480)")
    p.add_argument("--from", dest="t_from", type=option(SIM_TIME), default=None, metavar="S",
                   help="render from this sim time [s] on (default 0)")
    p.add_argument("--to", dest="t_to", type=option(SIM_TIME), default=None, metavar="S",
                   help="render up to this sim time [s] (default: the end)")
    p.add_argument("--progress", action="store_true",
                   help="report progress on stderr also when it is not a terminal (plain lines every 10 %%; on by "
                        "default when rendering)")
    p.add_argument("--view", action="store_true", help="open MuJoCo's interactive viewer (needs a display)")
    p.add_argument("--html", metavar="FILE",
                   help="write a replay page: one offline HTML file (3-D arm and blocks, timeline, move and suction "
                        "state, the halt on a fault); FILE#t=12.5 opens at 12.5 s")
    p.add_argument("--json", action="store_true", help="print one JSON object with the outcome on stdout")
    add_suction_profile_option(p)
    p.set_defaults(func=run)


def render_workers() -> int:
    """Processes rendering video frames: one per core the process may use (software GL renders one frame per
    core at a time), at most 8."""
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(1, min(8, cores))


def _check_render_options(args: argparse.Namespace) -> None:
    """Render settings only make sense with an output to render into."""
    given = [name for name, value in (("--fps", args.fps), ("--size", args.size), ("--from", args.t_from),
                                      ("--to", args.t_to)) if value is not None]
    if given and not (args.video or args.frames):
        raise UsageError(f"{', '.join(given)} set{'s' if len(given) == 1 else ''} how the run is rendered: use "
                         "with --video FILE or --frames DIR")
    check_window(args.t_from, args.t_to)


def _check_render_outputs(args: argparse.Namespace, inputs: list[Path]) -> Choice | None:
    """Refuse a video or frames path that cannot be written, before simulating anything; choose the OpenGL
    platform when the run renders (the choice; None: it does not)."""
    from ur3hanoi.io.atomic import check_output

    if args.html:
        require_replay()
        check_output(args.html, inputs=inputs)
    if args.video:
        try:
            import imageio_ffmpeg  # noqa: F401  (the "video" extra)
        except ImportError:
            raise UsageError("--video needs the video extra (imageio-ffmpeg, which ships ffmpeg): pip install "
                             "'ur3hanoi[video]'; or write PNG frames with --frames DIR") from None
    return check_render_outputs(args.video, args.frames, inputs)


def _table_calibration(args: argparse.Namespace) -> str:
    """The calibration to simulate on: given, the default one, or (for a real station's table) required."""
    if args.table is None:
        if args.key is not None:
            raise UsageError("--key names the key of a table to follow: use with --table FILE")
        return calibration_ref(args.calibration)
    if args.key is None:
        raise UsageError(f"--table needs --key ({' or '.join(TABLE_KEYS)}): which of the file's tables to follow")
    if args.calibration is None and args.key == "real_pos":
        raise UsageError("--key real_pos needs --calibration CAL: a real station's table fits only the station it "
                         f"was recorded on (sim_pos tables default to {DEFAULT_CALIBRATION})")
    return calibration_ref(args.calibration)


class _Job(NamedTuple):
    """What a ``solve`` run does, its options checked: the station, the instance and the table to follow."""

    station: Station
    start: int
    end: int
    n_blocks: int
    table: Any  # the visited entries of a recorded table (FloatArray), or None: generated waypoints
    inputs: list[Path]
    gl: Choice | None  # the OpenGL platform the run renders with (None: it does not render)


def _job(args: argparse.Namespace) -> _Job:
    """Every option checked (and the towers asked for on a terminal) before anything is simulated."""
    from ur3hanoi.hanoi import validate_instance
    from ur3hanoi.plan import PlanConfig
    from ur3hanoi.station.calibration import load_station

    _check_render_options(args)
    cal = _table_calibration(args)
    inputs = [input_file(cal)]
    station = load_station(cal)
    if args.suction_profile is not None:
        from ur3hanoi.station.calibration import with_suction_profile

        station = with_suction_profile(station, args.suction_profile)
    recorded = None
    if args.table is not None:
        from ur3hanoi.plan import check_table_shape
        from ur3hanoi.tables import read_recorded_table

        inputs.append(Path(args.table))
        # Entries may be missing (null, or no "above" list) as students record them: the entries the solve visits
        # must be there (RecordedTable.for_solve, the rule ros-solve applies too), the others may be missing.
        recorded = read_recorded_table(args.table, args.key)
        check_table_shape(recorded.q, station, f"{args.table}:{args.key}")
    n_towers = station.n_towers
    n_blocks = station.n_heights if args.blocks is None else args.blocks
    check_blocks(n_blocks, station.n_heights, given=args.blocks is not None)
    start, end = towers(args, n_towers, f"{station.name} has {n_towers} towers" if station.name else "", "solve")
    validate_instance(n_blocks, start, end, n_towers, station.n_heights)
    table = recorded.for_solve(start, end, n_blocks) if recorded is not None else None
    check_faults(args.remove_block, args.drop_during_move, n_blocks)
    plan_config = PlanConfig(speed=args.speed)
    check_plan_size(n_blocks, args.speed, plan_config.dwell_s, plan_config.rate_hz)
    gl = _check_render_outputs(args, inputs)  # MuJoCo is imported after this, with the platform chosen
    return _Job(station, start, end, n_blocks, table, inputs, gl)


def _sink(args: argparse.Namespace, job: _Job, scene: TaskScene) -> tuple[object | None, ProgressFn | None]:
    """(frame sink: the viewer, the offscreen recorder or none; the simulation's progress)."""
    from ur3hanoi.sim import CameraConfig, OffscreenRecorder, ViewerSink

    if args.view:
        return ViewerSink(scene.model, scene.data), None
    if job.gl is None:
        return None, progress_sink(args, None)
    print(f"ur3hanoi solve: rendering with {job.gl.describe()}", file=sys.stderr, flush=True)
    workers = render_workers()
    sim_progress, render_progress = (phases(progress_sink(args, None)) if workers > 1  # frames render afterwards
                                     else (None, None))
    default = CameraConfig()
    width, height = args.size if args.size is not None else (default.width, default.height)
    camera = CameraConfig(width=width, height=height, fps=args.fps if args.fps is not None else default.fps)
    sink = OffscreenRecorder(job.station, scene.model, frames_dir=Path(args.frames) if args.frames else None,
                             video=Path(args.video) if args.video else None, camera=camera,
                             t_from=args.t_from or 0.0, t_to=args.t_to, workers=workers, progress=render_progress)
    return sink, sim_progress if sim_progress is not None else progress_sink(args, sink)


def _simulate(args: argparse.Namespace, job: _Job, plan: Plan, scene: TaskScene, faults: Any, config: Any
              ) -> tuple[SimResult, Ur3HanoiError | None, Any, Any]:
    """Run ``plan`` in ``scene`` with the sinks the options ask for: (result, the suction fault that halted it or
    None, the frame sink, the replay recorder). An interrupted or failed run leaves an existing video as it was."""
    from ur3hanoi.sim import OffscreenRecorder, SimResult, run_plan

    sink, sim_progress = _sink(args, job, scene)
    frames, replay = sink, None
    fault: Ur3HanoiError | None = None
    try:
        if args.html:
            from ur3hanoi.replay import REPLAY_FPS, PoseRecorder, SinkTee

            replay = PoseRecorder(scene.model, REPLAY_FPS)
            frames = replay if sink is None else SinkTee([sink, replay])  # type: ignore[list-item]
        try:
            result = run_plan(plan, faults, config, frames=frames,  # type: ignore[arg-type]
                              progress=sim_progress, scene=scene, realtime=args.view)
        except SuctionFaultError as exc:
            # A halted run still has a result to report (the final block positions, the halt).
            if not isinstance(exc.result, SimResult):
                raise
            result, fault = exc.result, exc
        if isinstance(sink, OffscreenRecorder):
            sink.render_pending()  # the frames, in parallel processes (progress per frame)
    except BaseException:
        if isinstance(sink, OffscreenRecorder):
            sink.discard()
        raise
    finally:
        if sink is not None:
            sink.close()  # type: ignore[attr-defined]
    return result, fault, sink, replay


def run(args: argparse.Namespace) -> int:
    job = _job(args)  # first: it chooses the OpenGL platform, which MuJoCo reads when it is imported
    from ur3hanoi.plan import PlanConfig, plan_solve, plan_table
    from ur3hanoi.sim import Faults, SimConfig, build_task_scene, display_available

    station, start, end, n_blocks = job.station, job.start, job.end, job.n_blocks
    if args.view and display_available() is not None:
        raise UsageError(f"--view cannot open the MuJoCo viewer: {display_available()}; "
                         "use --video FILE.mp4 or --frames DIR")
    faults = Faults(
        remove_block=None if args.remove_block is None else args.remove_block - 1,
        drop_during_move=None if args.drop_during_move is None else args.drop_during_move - 1,
    )
    plan_config = PlanConfig(speed=args.speed)
    if job.table is not None:
        plan = plan_table(station, job.table, start, end, n_blocks, plan_config, where=f"{args.table}:{args.key}")
    else:
        plan = plan_solve(station, start, end, n_blocks, plan_config)
    if args.t_from is not None and args.t_from >= plan.duration_s:
        raise UsageError(f"--from {args.t_from:g} is invalid: the planned motion lasts {plan.duration_s:.2f} s of "
                         "sim time: expected an earlier time")
    config = SimConfig(seed=args.seed)
    scene = build_task_scene(station, start, n_blocks, faults.remove_block, config.scene)
    result, fault, sink, replay = _simulate(args, job, plan, scene, faults, config)
    html_size = None
    if args.html:
        from ur3hanoi.replay import write_run_replay

        following = f", following {args.table}:{args.key}" if args.table is not None else ""
        title = (f"{station.name}: {n_blocks} blocks, tower {start + 1} -> {end + 1}{following}: {result.status} "
                 f"({result.moves_completed}/{result.moves_total} moves)")
        html_size = write_run_replay(args.html, plan, scene, replay, result, title, tuple(job.inputs))
    _print_outcome(args, job, result, sink, html_size)
    if fault is not None:
        print(f"ur3hanoi: error: {' '.join(str(fault).split())}", file=sys.stderr)
        return exit_codes.exit_code_for(fault)
    if result.error is not None:
        print(f"ur3hanoi: error: {' '.join(str(result.error).split())}", file=sys.stderr)
    return int(result.exit_code)


def _print_outcome(args: argparse.Namespace, job: _Job, result: SimResult, sink: Any,
                   html_size: int | None) -> None:
    """The outcome on stdout: one JSON object with ``--json``, else a summary with every block's place."""
    station = job.station
    if args.json:
        import json

        out = result.as_dict()
        out["suction"] = station.suction.as_dict()
        if args.table is not None:
            out["table"] = {"file": str(args.table), "key": args.key}
        print(json.dumps(out))
        return
    following = f", following {shown(args.table)}:{args.key}" if args.table is not None else ""
    print(f"{result.status}: {result.moves_completed}/{result.moves_total} moves, tower {job.start + 1} -> "
          f"{job.end + 1}, {len(result.final_blocks)} blocks on {shown(station.name)}{following} (suction profile "
          f"{station.suction.name})")
    for b in result.final_blocks:
        where = "in no slot"
        if b.tower is not None and b.height is not None:
            where = f"tower {b.tower + 1} height {b.height + 1}"
        print(f"  block {b.block + 1} ({b.as_dict()['colour']}): {where} at "
              f"[{b.xyz[0]:.4f}, {b.xyz[1]:.4f}, {b.xyz[2]:.4f}] m")
    print(f"  sim {result.sim_time_s:.2f} s in {result.wall_time_s:.2f} s wall ({result.realtime_factor:.1f}x "
          f"real time), max tracking error {math.degrees(result.max_tracking_error_rad):.3f} deg, suction "
          f"{'on' if result.suction_on_at_end else 'off'}, {'at' if result.at_home_at_end else 'not at'} home")
    if args.video or args.frames:
        print(f"  wrote {sink.count} frames to {shown(args.video or args.frames)}")
    if html_size is not None:
        print(f"  wrote the replay page {shown(args.html)} ({html_size / 1e6:.1f} MB)")
