"""Small pieces shared by the commands: the default station, input file paths, printable names."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ur3hanoi.errors import printable

if TYPE_CHECKING:
    from ur3hanoi.opengl import Choice

DEFAULT_CALIBRATION = "lab_sim"

SYMLINK_NOTE = "written atomically; a symlink is written through to its target"


def calibration_ref(arg: str | None) -> str:
    """``--calibration`` (a file or a shipped station name), or the shipped default station."""
    return DEFAULT_CALIBRATION if arg is None else arg


def input_file(ref: str) -> Path:
    """The file behind a calibration argument (a shipped station name or a path)."""
    from ur3hanoi.io.resources import station_file

    return station_file(ref)


def check_render_outputs(video: str | None, frames: str | None, inputs: Sequence[Path] = ()) -> Choice | None:
    """Refuse a ``--video`` file or ``--frames`` folder that cannot be written, before any work (the rules of
    :mod:`ur3hanoi.io.atomic`), and choose the OpenGL platform to render with (:func:`ur3hanoi.opengl.use_platform`,
    before MuJoCo is imported: call this first). Returns the choice (None: nothing to render)."""
    from ur3hanoi.io.atomic import check_output, check_output_dir
    from ur3hanoi.opengl import use_platform

    if video:
        check_output(video, inputs=inputs)  # first: "it is a directory" says more than "no extension"
    if frames:
        check_output_dir(frames, inputs=inputs)
    if not (video or frames):
        return None
    choice = use_platform()
    if video:
        from ur3hanoi.sim.render import check_video_path  # imports MuJoCo

        check_video_path(video)
    return choice


def shown(path: Any) -> str:
    """A user-given path as printed on the terminal (control characters escaped)."""
    return printable(path, 4096)


SUCTION_PROFILES: tuple[str, ...] = ("lab_sim", "real")
"""The names of :data:`ur3hanoi.station.suction_profile.PROFILES` for ``--suction-profile``, spelt out so that building
the parser does not import the profiles (tests/cli/test_startup.py checks that both are the same)."""


def add_suction_profile_option(p: Any) -> None:
    """``--suction-profile NAME``: a named suction feedback profile instead of the calibration's ``suction``."""
    p.add_argument("--suction-profile", choices=SUCTION_PROFILES, default=None,
                   help="suction feedback levels (DIGIN/AIN0 held, cup free, off): lab_sim = the course simulator's "
                        "(~1.9/1.45/1.05 V), real = a real station's (2.35/1.40/1.05 V); default: the "
                        "calibration's suction section (lab_sim without one)")


def require_replay() -> None:
    """``--html`` needs meshcat's viewer (the ``replay`` extra; placo installs it too): one line naming the extra."""
    import importlib.util

    from ur3hanoi.cli.options import UsageError

    if importlib.util.find_spec("meshcat") is None or importlib.util.find_spec("umsgpack") is None:
        raise UsageError("--html needs meshcat (its three.js viewer), which is not installed: pip install "
                         "'ur3hanoi[replay]'")
