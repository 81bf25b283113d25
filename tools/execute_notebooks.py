#!/usr/bin/env python3
"""Execute the notebooks in place from a clean kernel and keep their outputs (plots, tables), so they render on a
code-hosting page. tests/test_notebooks.py checks that re-executing them reproduces the committed outputs'
structure: run this after changing a notebook or what it shows.

Usage: .venv/bin/python tools/execute_notebooks.py [notebooks/NAME.ipynb ...]   (default: all)
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient

REPO = Path(__file__).resolve().parents[1]


def execute(nb: nbformat.NotebookNode, directory: Path) -> nbformat.NotebookNode:
    """Run every cell of ``nb`` in a fresh kernel (matplotlib's inline backend: figures become PNG outputs)."""
    # The kernel's inline backend, not Agg: the figures are the outputs (the caller's setting is restored).
    saved = os.environ.pop("MPLBACKEND", None)
    try:
        client = NotebookClient(nb, timeout=900, kernel_name="python3", record_timing=False,
                                resources={"metadata": {"path": str(directory)}})
        client.execute()
    finally:
        if saved is not None:
            os.environ["MPLBACKEND"] = saved
    return nb


def main(argv: list[str]) -> int:
    paths = [Path(a) for a in argv] or sorted((REPO / "notebooks").glob("*.ipynb"))
    for path in paths:
        nb = nbformat.read(path, as_version=4)
        execute(nb, path.parent)
        nb.metadata.pop("widgets", None)
        nbformat.write(nb, path)
        print(f"executed {path.relative_to(REPO) if path.is_absolute() else path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
