"""Rewrite the README's CLI reference from the parser (`make docs`); tests/cli/test_main.py fails when it is stale."""

from __future__ import annotations

import sys
from pathlib import Path

from ur3hanoi.cli import help_markdown

START, END = "<!-- cli-reference:start -->", "<!-- cli-reference:end -->"


def render(readme: str) -> str:
    head, rest = readme.split(START, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{START}\n{help_markdown()}{END}{tail}"


if __name__ == "__main__":
    path = Path(__file__).resolve().parents[1] / "README.md"
    path.write_text(render(path.read_text()))
    sys.exit(0)
