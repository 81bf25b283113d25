"""The notebooks are committed with their outputs (so they render on a code-hosting page), executed in order from a
clean kernel, and re-executing them reproduces the committed outputs' structure: the same cells, the same kinds of
output in each (printed text, figures as PNG, tables), the same number of printed lines. A notebook edited without
re-running ``tools/execute_notebooks.py`` fails here."""

from __future__ import annotations

import copy
import sys
from pathlib import Path
from typing import Any

import nbformat
import pytest

from tests.conftest import REPO

NOTEBOOKS = sorted((REPO / "notebooks").glob("*.ipynb"))

sys.path.insert(0, str(REPO / "tools"))
from execute_notebooks import execute  # noqa: E402


def structure(nb: nbformat.NotebookNode) -> list[tuple[str, str, list[tuple[Any, ...]]]]:
    """Per cell: its type, its source, and its outputs as (kind, detail): printed text as ("stream", name, number
    of lines) with consecutive chunks of one stream merged (the kernel may split a print loop's text anywhere),
    stderr left out (library warnings differ between machines), rich outputs as (type, their MIME types)."""
    out = []
    for cell in nb.cells:
        outputs: list[tuple[Any, ...]] = []
        text = ""
        for o in cell.get("outputs", []):
            if o.output_type == "stream":
                if o.name == "stdout":
                    text += o.text
                continue
            if text:
                outputs.append(("stream", "stdout", text.count("\n")))
                text = ""
            if o.output_type == "error":
                outputs.append(("error", o.ename))
            else:
                outputs.append((o.output_type, tuple(sorted(o.get("data", {})))))
        if text:
            outputs.append(("stream", "stdout", text.count("\n")))
        out.append((cell.cell_type, cell.source, outputs))
    return out


def test_there_are_notebooks() -> None:
    assert [p.name for p in NOTEBOOKS][:1] == ["01_kinematics.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_notebook_is_committed_executed_in_order_with_outputs(path: Path) -> None:
    nb = nbformat.read(path, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1)), \
        f"{path.name}: execute it from a clean kernel: .venv/bin/python tools/execute_notebooks.py"
    shown = [o for c in code for o in c.outputs]
    assert any(o.output_type == "display_data" and "image/png" in o.data for o in shown), f"{path.name}: no figure"
    assert not [o for o in shown if o.output_type == "error"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_reexecuting_reproduces_the_committed_outputs(path: Path) -> None:
    committed = nbformat.read(path, as_version=4)
    fresh = copy.deepcopy(committed)
    for cell in fresh.cells:
        if cell.cell_type == "code":
            cell.outputs, cell.execution_count = [], None
    execute(fresh, path.parent)  # raises CellExecutionError naming the failing cell
    want, got = structure(committed), structure(fresh)
    assert len(got) == len(want)
    for i, (w, g) in enumerate(zip(want, got, strict=True)):
        assert g == w, (f"{path.name} cell {i}: re-executed outputs {g[2]} differ from the committed {w[2]}: "
                        "rerun .venv/bin/python tools/execute_notebooks.py")
