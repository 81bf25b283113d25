"""matplotlib for the pictures: a clear error when the ``plot`` extra is missing, the formats by extension, and
an atomic save (a failed or refused write leaves any old file unchanged)."""

from __future__ import annotations

import io
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ur3hanoi.errors import OutputError, Ur3HanoiError, printable, quote
from ur3hanoi.io.atomic import locked_output

if TYPE_CHECKING:
    from matplotlib.figure import Figure

PLOT_FORMATS = (".png", ".svg", ".pdf")
"""The picture file extensions (lower case) the ``--plot`` options write."""

INSTALL_HINT = "pip install 'ur3hanoi[plot]'"


class MissingExtraError(Ur3HanoiError):
    """An optional dependency (an extra of the package) is not installed (exit code 2)."""


def require_matplotlib() -> Any:
    """The ``matplotlib`` module with its non-interactive Agg backend, or a one-line error naming the extra."""
    try:
        import matplotlib
    except ImportError:
        raise MissingExtraError(f"pictures need matplotlib, which is not installed: {INSTALL_HINT}") from None
    matplotlib.use("Agg")
    return matplotlib


def check_plot_path(path: str | Path, inputs: tuple[Path, ...] = ()) -> str:
    """The picture format of ``path`` by its extension, after checking the file can be written.

    Raises:
        OutputError: an extension other than :data:`PLOT_FORMATS`, or a path that cannot be written.
    """
    from ur3hanoi.io.atomic import check_output

    check_output(path, inputs=inputs)
    ext = Path(path).suffix.lower()
    if ext not in PLOT_FORMATS:
        got = f"extension {quote(ext)}" if ext else "no extension"
        raise OutputError(f"cannot write the picture {printable(path)}: {got} is not a picture format ur3hanoi "
                          f"writes: expected one of {', '.join(PLOT_FORMATS)}")
    return ext[1:]


def save_figure(fig: Figure, path: str | Path, inputs: tuple[Path, ...] = (), dpi: int = 110) -> Path:
    """Render ``fig`` in memory, then replace ``path`` with it atomically; returns the file written."""
    fmt = check_plot_path(path, inputs)
    buf = io.BytesIO()
    fig.savefig(buf, format=fmt, dpi=dpi, bbox_inches="tight", metadata=_metadata(fmt))
    with locked_output(path, inputs=inputs) as out:
        out.write_bytes(buf.getvalue())
    return out.path


def _metadata(fmt: str) -> dict[str, Any]:
    """No creation date (the same figure gives the same file)."""
    if fmt == "svg":
        return {"Date": None}
    if fmt == "pdf":
        return {"CreationDate": None}
    return {}
