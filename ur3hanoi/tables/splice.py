"""Splicing keys into the text of a YAML document in place: every byte outside the replaced keys is kept.

The file is the student's. Writing key ``K`` replaces the text of ``K``'s entry, whatever it held (a table, junk
like ``sim_pos: old``, nothing), and keeps every other byte of the file: other keys (known to ur3hanoi or not,
valid or not), comments, blank lines, document markers, line endings and a byte-order mark. The entry's text runs
from the start of its key's line to the end of the last line holding its value; comments and blank lines after
that belong to what follows. ``K``'s provenance comment (``# ur3hanoi <version>: K generated from ...``, written
by ur3hanoi on the line above the key) goes with it. A new key is added after the last entry. A document whose top
level is not a mapping is refused.

Where the entries are is read from PyYAML's parser events (:func:`layout`), which carry each node's position.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any, NamedTuple

import yaml

from ur3hanoi.errors import TableError
from ur3hanoi.tables.format import FILE_HEADER, format_flow


class _Entry(NamedTuple):
    """A top-level key of the file: ``start`` (the key's first character), ``end`` (just past the value's last
    character) as text indices, and the key's text."""

    key: Any
    start: int
    end: int


class _Layout(NamedTuple):
    """Where the top-level mapping's entries are; ``flow`` for ``{...}``; ``close`` is the index of a flow
    mapping's ``}``."""

    entries: tuple[_Entry, ...]
    flow: bool
    close: int


def _at(mark: Any) -> int:
    return -1 if mark is None else int(mark.index)


def _layout(text: str) -> _Layout | None:
    """The top-level entries of a YAML document already parsed strictly (``None`` for an empty document).

    Walks the parser's events: an entry ends at the last scalar, alias or flow-collection end inside its value
    (block collections end where the next token starts, after any comments, so their own end is not used).
    """
    entries: list[_Entry] = []
    depth = 0
    flow_stack: list[bool] = []
    top_flow, close, is_key = False, -1, True
    key: Any = None
    start = end = -1
    for ev in yaml.parse(text, Loader=yaml.SafeLoader):
        if isinstance(ev, yaml.StreamStartEvent | yaml.StreamEndEvent | yaml.DocumentStartEvent
                      | yaml.DocumentEndEvent):
            continue
        if isinstance(ev, yaml.MappingEndEvent | yaml.SequenceEndEvent):
            depth -= 1
            was_flow = flow_stack.pop()
            if depth == 0:
                close = _at(ev.start_mark)
                break
            if was_flow:
                end = max(end, _at(ev.end_mark))
            continue
        # A node starts: a scalar, an alias or a collection.
        if depth == 0:
            if isinstance(ev, yaml.ScalarEvent) and ev.value == "" and ev.implicit[0]:
                return None  # an empty document (`---` alone)
            if not isinstance(ev, yaml.MappingStartEvent):
                return _Layout((), False, -1)
            top_flow = bool(ev.flow_style)
            depth = 1
            flow_stack.append(top_flow)
            continue
        if depth == 1:
            if is_key:
                if start >= 0:
                    entries.append(_Entry(key, start, end))
                key = ev.value if isinstance(ev, yaml.ScalarEvent) else None
                start = _at(ev.start_mark)
            is_key = not is_key
        if isinstance(ev, yaml.MappingStartEvent | yaml.SequenceStartEvent):
            depth += 1
            flow_stack.append(bool(ev.flow_style))
        else:
            end = max(end, _at(ev.end_mark))
    if start >= 0:
        entries.append(_Entry(key, start, end))
    if close < 0 and not entries:
        return None  # no document at all (empty, blank or comments only)
    return _Layout(tuple(entries), top_flow, close)


def _line_start(text: str, i: int) -> int:
    return text.rfind("\n", 0, i) + 1


def _line_end(text: str, i: int) -> int:
    """Index just past the end of the line holding index ``i - 1`` (its newline included)."""
    j = text.find("\n", max(i - 1, 0))
    return len(text) if j < 0 else j + 1


def _entry_end(text: str, e: _Entry) -> int:
    """Just past the last line of an entry holding its value: a block scalar's trailing blank lines belong to what
    follows, like comments do."""
    end = _line_end(text, e.end)
    first = _line_end(text, e.start + 1)
    while end > first:
        prev = _line_start(text, end - 1)
        if text[prev:end].strip():
            break
        end = prev
    return end


def _provenance_re(key: str) -> re.Pattern[str]:
    return re.compile(rf"^# ur3hanoi \S+: {re.escape(key)} generated from .*\r?\n?", re.MULTILINE)


def splice_yaml(old_text: str, new_sections: Mapping[str, str], header_lines: Mapping[str, str],
                flow_values: Mapping[str, Any] | None = None) -> str:
    """Replace (or add) the given top-level keys of a YAML document, keeping every other byte.

    Args:
        old_text: the document (already known to parse as YAML, top level a mapping or empty).
        new_sections: key -> block-YAML text of ``key: value`` (unindented, ending in a newline).
        header_lines: key -> its provenance comment line (no newline), written on the line above the key.
        flow_values: key -> the value, for a document whose top-level mapping is in flow style (``{...}``).

    Raises:
        TableError: the document's top level is not a mapping.
    """
    layout = _layout(old_text)
    nl = "\r\n" if "\r\n" in old_text else "\n"

    def block(key: str, indent: str) -> str:
        lines = [header_lines[key], *new_sections[key].splitlines()] if key in header_lines else \
            new_sections[key].splitlines()
        return "".join(indent + line + nl for line in lines)

    if layout is None:  # empty, blank or comments only
        text = old_text if old_text.strip() else FILE_HEADER.replace("\n", nl)
        if text and not text.endswith("\n"):
            text += nl
        return text + "".join(block(k, "") for k in new_sections)
    if not layout.entries and layout.close < 0:
        raise TableError("the top level is not a mapping")
    edits: list[tuple[int, int, str]] = []  # (start, end, replacement), non-overlapping
    done: set[str] = set()
    for e in layout.entries:
        if not isinstance(e.key, str) or e.key not in new_sections or e.key in done:
            continue
        done.add(e.key)
        if layout.flow:
            edits.append((e.start, e.end, f"{e.key}: {format_flow((flow_values or {})[e.key])}"))
            continue
        start = _line_start(old_text, e.start)
        before = old_text[start:e.start]
        indent = before[:len(before) - len(before.lstrip(" "))]
        if before.strip() not in ("", "?"):  # something else before the key on its line: replace from the key on
            start, indent = e.start, ""
        # The key's own provenance comment right above it goes with it.
        prov = _provenance_re(e.key)
        while start > 0:
            prev = _line_start(old_text, start - 1)
            if not prov.fullmatch(old_text[prev:start].lstrip(" ")):
                break
            start = prev
        edits.append((start, _entry_end(old_text, e), block(e.key, indent)))
    new_keys = [k for k in new_sections if k not in done]
    if new_keys:
        if layout.flow:
            sep = ", " if layout.entries else ""
            edits.append((layout.close, layout.close,
                          sep + ", ".join(f"{k}: {format_flow((flow_values or {})[k])}" for k in new_keys)))
        else:
            last = max(layout.entries, key=lambda e: e.end)
            at = _entry_end(old_text, last)
            indent = old_text[_line_start(old_text, last.start):last.start]
            indent = "" if indent.strip() else indent
            pre = nl if at == len(old_text) and not old_text.endswith("\n") else ""
            edits.append((at, at, pre + "".join(block(k, indent) for k in new_keys)))
    # Stale provenance lines of a replaced key elsewhere (the header of files written before 0.2) go too.
    spans = [(a, b) for a, b, _ in edits]
    for k in new_sections:
        for m in _provenance_re(k).finditer(old_text):
            if not any(a <= m.start() < b for a, b in spans):
                edits.append((m.start(), m.end(), ""))
    out, pos = [], 0
    for a, b, repl in sorted(edits, key=lambda x: (x[0], x[1])):
        out.append(old_text[pos:a])
        out.append(repl)
        pos = max(pos, b)
    out.append(old_text[pos:])
    return "".join(out)


__all__ = ["splice_yaml"]
