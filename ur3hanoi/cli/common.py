"""Small pieces shared by the commands: the default station, input file paths, printable names."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ur3hanoi.errors import printable
from ur3hanoi.resources import station_file

DEFAULT_CALIBRATION = "lab_sim"

SYMLINK_NOTE = "written atomically; a symlink is written through to its target"


def calibration_ref(arg: str | None) -> str:
    """``--calibration`` (a file or a shipped station name), or the shipped default station."""
    return DEFAULT_CALIBRATION if arg is None else arg


def input_file(ref: str) -> Path:
    """The file behind a calibration argument (a shipped station name or a path)."""
    return station_file(ref)


def shown(path: Any) -> str:
    """A user-given path as printed on the terminal (control characters escaped)."""
    return printable(path, 4096)


def require_replay() -> None:
    """``--html`` needs meshcat's viewer (the ``replay`` extra; placo installs it too): one line naming the extra."""
    import importlib.util

    from ur3hanoi.cli.options import UsageError

    if importlib.util.find_spec("meshcat") is None or importlib.util.find_spec("umsgpack") is None:
        raise UsageError("--html needs meshcat (its three.js viewer), which is not installed: pip install "
                         "'ur3hanoi[replay]'")
