"""Rewrite the generated part of the command-line reference, docs/cli.md, from the parser (`make docs`).

tests/test_docs.py fails when the page is stale. The text above the start marker is written by hand.
"""

from __future__ import annotations

import sys
from pathlib import Path

from ur3hanoi.cli import help_markdown

START, END = "<!-- cli-reference:start -->", "<!-- cli-reference:end -->"
PAGE = Path(__file__).resolve().parents[1] / "docs" / "cli.md"


def render(page: str) -> str:
    """``page`` with everything between the markers replaced by the parser's help."""
    head, rest = page.split(START, 1)
    _, tail = rest.split(END, 1)
    return f"{head}{START}\n{help_markdown()}{END}{tail}"


if __name__ == "__main__":
    PAGE.write_text(render(PAGE.read_text()))
    sys.exit(0)
