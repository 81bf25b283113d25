"""Helpers of the documentation tests: the pages, their fenced shell blocks and the markers that say what a test
does with each block (see docs/design.md, "Runnable blocks").

A fenced ``bash`` block is preceded by an HTML comment: ``<!-- run -->`` (optionally ``: slow``, ``ros``, ``dds``,
``background``, ``exit N``, comma-separated) or ``<!-- shown: REASON -->``. :func:`shell_blocks` reads them and
refuses a page whose shell block has no marker, a marker with an unknown word, or a ``shown`` without a reason.
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
DOCS = REPO / "docs"
SHELL_LANGS = frozenset({"bash", "sh", "shell", "console"})
PHASES = ("cpu", "slow", "dds", "ros")
"""The phases a page's blocks can need, lightest first: a page runs whole in the heaviest of its blocks'."""

_MARKER = re.compile(r"^<!--\s*(run|shown)\s*(?::\s*(.*?))?\s*-->\s*$")
_FENCE = re.compile(r"^(`{3,})\s*([\w-]*)")


class PageError(ValueError):
    """A page's blocks or markers break the convention; the message names the page and line."""


@dataclass(frozen=True)
class Block:
    """One fenced shell block of a page and what its marker says."""

    page: str
    line: int  # 1-based line of the opening fence
    run: bool
    phase: str = "cpu"
    background: bool = False
    exit_code: int = 0  # of the block's last command; every other one must exit 0
    reason: str = ""  # why a shown block is not run
    text: str = ""

    @property
    def where(self) -> str:
        return f"{self.page}:{self.line}"

    def commands(self) -> list[str]:
        """The block's commands, one per line (``\\`` continuations joined), comments and blank lines left out."""
        joined = re.sub(r"\\\n\s*", " ", self.text)
        return [ln.strip() for ln in joined.splitlines() if ln.strip() and not ln.strip().startswith("#")]


def doc_pages() -> list[Path]:
    """The README and every Markdown page of the site (the notebooks are not Markdown pages)."""
    return [REPO / "README.md", *sorted(p for p in DOCS.glob("*.md"))]


def page_name(path: Path) -> str:
    """``path`` relative to the repository (as pages are named in messages), or as given outside it."""
    return str(path.relative_to(REPO)) if path.is_relative_to(REPO) else str(path)


def _parse_marker(kind: str, words: str | None, where: str, line: int, text: str) -> Block:
    if kind == "shown":
        if not words:
            raise PageError(f"{where}: a shown block needs a reason: <!-- shown: REASON -->")
        return Block(where.split(":")[0], line, run=False, reason=words, text=text)
    phase, background, exit_code = "cpu", False, 0
    for word in (w.strip() for w in (words or "").split(",") if w.strip()):
        if word in PHASES:
            phase = max(phase, word, key=PHASES.index)
        elif word == "background":
            background = True
        elif re.fullmatch(r"exit \d+", word):
            exit_code = int(word.split()[1])
        else:
            raise PageError(f"{where}: unknown word {word!r} in a run marker (expected {', '.join(PHASES[1:])}, "
                            "background, exit N)")
    block = Block(where.split(":")[0], line, run=True, phase=phase, background=background, exit_code=exit_code,
                  text=text)
    if background and (len(block.commands()) != 1 or exit_code):
        raise PageError(f"{where}: a background block holds exactly one command and no exit code")
    return block


def shell_blocks(path: Path) -> list[Block]:
    """Every fenced shell block of ``path`` with its marker, in page order."""
    name, lines = page_name(path), path.read_text(encoding="utf-8").splitlines()
    blocks, i = [], 0
    while i < len(lines):
        m = _FENCE.match(lines[i])
        if not m:
            i += 1
            continue
        end = next((j for j in range(i + 1, len(lines)) if lines[j].strip() == m.group(1)), None)
        if end is None:
            raise PageError(f"{name}:{i + 1}: a fenced block that never closes")
        if m.group(2) in SHELL_LANGS:
            prev = lines[i - 1].strip() if i else ""
            marker = _MARKER.match(prev)
            if marker is None:
                raise PageError(f"{name}:{i + 1}: a shell block without a marker on the line before it "
                                "(<!-- run --> or <!-- shown: REASON -->, see docs/design.md)")
            blocks.append(_parse_marker(marker.group(1), marker.group(2), f"{name}:{i + 1}", i + 1,
                                        "\n".join(lines[i + 1:end])))
        i = end + 1
    return blocks


def page_phase(blocks: list[Block]) -> str:
    """The phase a page runs in: that of its heaviest run block."""
    return max((b.phase for b in blocks if b.run), key=PHASES.index, default="cpu")


PRELUDE = r"""
ur3hanoi_bg=()
stop_background() {  # on every exit path: stop what the page started in the background
  for pid in "${ur3hanoi_bg[@]}"; do kill -TERM "$pid" 2>/dev/null; done
}
trap stop_background EXIT
wait_ready() {  # wait_ready PID OUT ERR: until the background command printed its ready line on stderr (120 s at
  # most): a station's stdout is its JSON report alone
  for _ in $(seq 1 1200); do
    grep -qs "ready" "$3" && return 0
    kill -0 "$1" 2>/dev/null || return 1
    sleep 0.1
  done
  return 1
}
fail() { echo "DOCS-FAIL $*" >&2; exit 90; }
"""


def page_script(blocks: list[Block]) -> str:
    """One bash script that runs a page's run blocks in order and fails (exit 90, ``DOCS-FAIL where: why`` on
    stderr) at the first command whose exit status is not the one the page says; background blocks are stopped
    with SIGTERM at the end and must then exit 0."""
    out = [PRELUDE]
    for k, b in enumerate(b for b in blocks if b.run):
        if b.background:
            log = f"background-{k}"
            out += [f"{b.commands()[0]} > {log}.out 2> {log}.err &",
                    f"pid{k}=$!; ur3hanoi_bg+=($pid{k})",
                    f"wait_ready $pid{k} {log}.out {log}.err || {{ cat {log}.out {log}.err >&2; "
                    f"fail {shlex.quote(b.where + ': no ready line from the background command')}; }}"]
            continue
        cmds = b.commands()
        for n, cmd in enumerate(cmds):
            want = b.exit_code if n == len(cmds) - 1 else 0
            why = shlex.quote(f"{b.where}: {cmd!r} exited $rc, the page expects {want}")
            out += [cmd, f'rc=$?; [ "$rc" -eq {want} ] || fail {why.replace("$rc", chr(39) + "$rc" + chr(39))}']
    for k, b in enumerate(b for b in blocks if b.run):
        if b.background:
            why = shlex.quote(f"{b.where}: the background command exited $rc after SIGTERM, not 0")
            out += [f"kill -TERM $pid{k}; wait $pid{k}; rc=$?",
                    f'[ "$rc" -eq 0 ] || fail {why.replace("$rc", chr(39) + "$rc" + chr(39))}']
    out += ["trap - EXIT", "echo DOCS-OK"]
    return "\n".join(out) + "\n"
