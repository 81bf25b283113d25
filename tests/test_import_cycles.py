"""No import cycles in the ur3hanoi package: dependencies flow one way.

The import graph is read from the source with :mod:`ast`, not by importing. Every ``import`` statement counts:
at module level, under ``if TYPE_CHECKING:`` or ``try:``, and inside functions, because a lazy or typing-only
import only delays a dependency, it does not remove it (the cycles of issue 18 were of both kinds:
``errors -> sim.result`` under TYPE_CHECKING, ``ros.env -> ros.msgs`` inside a function).
``from a.b import c`` is an edge to the submodule ``a.b.c`` when there is one, else to ``a.b``; a package's
``__init__`` importing its own submodules is an edge like any other.
"""

from __future__ import annotations

import ast
from collections import deque
from pathlib import Path

import ur3hanoi

PACKAGE_DIR = Path(ur3hanoi.__file__).resolve().parent

KNOWN_CYCLES: frozenset[frozenset[str]] = frozenset()
"""Cycles tolerated for now (none): an entry here must name a tracked issue."""


def module_files(package_dir: Path = PACKAGE_DIR) -> dict[str, Path]:
    """``{dotted module name: file}`` for every ``.py`` file of the package (``__init__`` names the package)."""
    out: dict[str, Path] = {}
    for path in sorted(package_dir.rglob("*.py")):
        parts = list(path.relative_to(package_dir.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def imports_of(name: str, files: dict[str, Path]) -> set[str]:
    """The package's modules that module ``name`` imports anywhere in its source."""
    path = files[name]
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    out: set[str] = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            out.update(alias.name for alias in node.names if alias.name in files)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                module = ".".join([*base, *([node.module] if node.module else [])])
            else:
                module = node.module or ""
            for alias in node.names:
                if f"{module}.{alias.name}" in files:
                    out.add(f"{module}.{alias.name}")
                elif module in files:
                    out.add(module)
    out.discard(name)
    return out


def import_graph(files: dict[str, Path]) -> dict[str, set[str]]:
    return {name: imports_of(name, files) for name in files}


def cyclic_groups(graph: dict[str, set[str]]) -> list[frozenset[str]]:
    """The strongly connected components with more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    groups: list[frozenset[str]] = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            node, children = work[-1]
            child = next(children, None)
            if child is not None:
                if child not in index:
                    index[child] = low[child] = len(index)
                    stack.append(child)
                    on_stack.add(child)
                    work.append((child, iter(sorted(graph[child]))))
                elif child in on_stack:
                    low[node] = min(low[node], index[child])
                continue
            work.pop()
            if work:
                low[work[-1][0]] = min(low[work[-1][0]], low[node])
            if low[node] == index[node]:
                group = []
                while True:
                    member = stack.pop()
                    on_stack.discard(member)
                    group.append(member)
                    if member == node:
                        break
                if len(group) > 1:
                    groups.append(frozenset(group))
    return groups


def a_cycle(group: frozenset[str], graph: dict[str, set[str]]) -> list[str]:
    """One shortest cycle through the group's first module, for the failure message: ``[a, b, ..., a]``."""
    start = min(group)
    parent: dict[str, str] = {}
    queue = deque([start])
    while queue:
        node = queue.popleft()
        for child in sorted(graph[node] & group):
            if child == start:
                path = [node]
                while path[-1] != start:
                    path.append(parent[path[-1]])
                return [*reversed(path), start]
            if child not in parent:
                parent[child] = node
                queue.append(child)
    raise AssertionError(f"{sorted(group)} is not a cycle")


def test_no_import_cycles() -> None:
    graph = import_graph(module_files())
    unexpected = [g for g in cyclic_groups(graph) if g not in KNOWN_CYCLES]
    assert not unexpected, "import cycles: " + "; ".join(" -> ".join(a_cycle(g, graph)) for g in unexpected)


def test_the_graph_sees_every_kind_of_import(tmp_path: Path) -> None:
    """The detector itself: module-level, TYPE_CHECKING, function-level, relative and from-package imports make
    edges, and a cycle through any of them is found."""
    pkg = tmp_path / "pkg"
    (pkg / "sub").mkdir(parents=True)
    sources = {
        "__init__.py": "",
        "a.py": "from pkg import b\n",
        "b.py": "from typing import TYPE_CHECKING\nif TYPE_CHECKING:\n    from pkg.sub.c import X\n",
        "sub/__init__.py": "",
        "sub/c.py": "def f():\n    from .. import a\n    return a\nX = 1\n",
        "d.py": "import pkg.a\nimport os\n",
    }
    for rel, text in sources.items():
        (pkg / rel).write_text(text)
    graph = import_graph(module_files(pkg))
    assert graph == {"pkg": set(), "pkg.a": {"pkg.b"}, "pkg.b": {"pkg.sub.c"}, "pkg.sub": set(),
                     "pkg.sub.c": {"pkg.a"}, "pkg.d": {"pkg.a"}}
    assert cyclic_groups(graph) == [frozenset({"pkg.a", "pkg.b", "pkg.sub.c"})]
    assert a_cycle(frozenset({"pkg.a", "pkg.b", "pkg.sub.c"}), graph) == ["pkg.a", "pkg.b", "pkg.sub.c", "pkg.a"]
    (pkg / "sub/c.py").write_text("X = 1\n")  # without the lazy import: no cycle
    assert cyclic_groups(import_graph(module_files(pkg))) == []


TEACH_NEVER_REACHES = ("ur3hanoi.remote", "ur3hanoi.ros", "ur3hanoi.ros2", "ur3hanoi.cli", "ur3hanoi.sim",
                       "ur3hanoi.replay", "ur3hanoi.plots")
"""``ur3hanoi.teach`` sits beside the transports: it reaches none of them (nor the command line, the simulator or
the pictures), directly or through what it imports; the command line passes it a driver client."""


def test_teach_reaches_no_transport() -> None:
    graph = import_graph(module_files())
    reached: set[str] = set()
    todo = [m for m in graph if m == "ur3hanoi.teach" or m.startswith("ur3hanoi.teach.")]
    while todo:
        node = todo.pop()
        for child in graph[node] - reached:
            reached.add(child)
            todo.append(child)
    bad = sorted(m for m in reached if any(m == p or m.startswith(f"{p}.") for p in TEACH_NEVER_REACHES))
    assert not bad, f"ur3hanoi.teach reaches {bad}"
