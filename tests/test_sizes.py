"""Small rooms: no module of the package over 400 lines, no function over 80, no class over 200 (decorators and
docstrings included, as a reader scrolls them).

Measured on every module of the package, its folders one by one (a failure names the folder) and the loose
modules.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from tests.support import REPO

PACKAGE = REPO / "ur3hanoi"
CHECKED = ("", *sorted(p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()))
"""The loose modules (``""``) and every folder of the package."""
MAX_MODULE, MAX_FUNCTION, MAX_CLASS = 400, 80, 200


def oversized(path: Path, root: Path = PACKAGE) -> list[str]:
    """What in the module ``path`` is over the limits, as ``file: what (n lines > limit)``."""
    text = path.read_text(encoding="utf-8")
    rel = path.relative_to(root).as_posix()
    out = []
    n = len(text.splitlines())
    if n > MAX_MODULE:
        out.append(f"{rel}: module ({n} lines > {MAX_MODULE})")
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.ClassDef):
            first = min([node.lineno, *(d.lineno for d in node.decorator_list)])
            size = (node.end_lineno or node.lineno) - first + 1
            limit = MAX_CLASS if isinstance(node, ast.ClassDef) else MAX_FUNCTION
            if size > limit:
                out.append(f"{rel}: {node.name} ({size} lines > {limit})")
    return out


@pytest.mark.parametrize("folder", CHECKED)
def test_rooms_are_small(folder: str) -> None:
    modules = sorted((PACKAGE / folder).rglob("*.py") if folder else PACKAGE.glob("*.py"))
    assert modules
    assert [line for path in modules for line in oversized(path)] == []


def test_an_oversized_room_is_found(tmp_path: Path) -> None:
    body = "".join(f"    x{i} = {i}\n" for i in range(80))
    method = "    @staticmethod\n    def g() -> None:\n" + body.replace("    x", "        x")
    source = f"def f() -> None:\n{body}\n\nclass C:\n{method * 3}" + "\n" * 150
    path = tmp_path / "m.py"
    path.write_text(source, encoding="utf-8")
    found = oversized(path, tmp_path)
    assert found == ["m.py: module (480 lines > 400)", "m.py: f (81 lines > 80)", "m.py: C (247 lines > 200)",
                     "m.py: g (82 lines > 80)", "m.py: g (82 lines > 80)", "m.py: g (82 lines > 80)"], found
