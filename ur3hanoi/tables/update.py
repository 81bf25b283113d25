"""Writing generated keys into a lab table file: the locked read-modify-write that ends in an atomic replace.

:func:`write_sections` takes the keys' text as already formatted (:class:`~ur3hanoi.tables.sections.Sections`)
and needs no NumPy. Under the output's lock (:func:`ur3hanoi.io.atomic.locked_output`, so concurrent writers of
different keys never lose one) it reads the file (strict YAML, its top level a mapping: anything else is refused and the
file left byte-identical), splices the keys in (:mod:`~ur3hanoi.tables.splice`: every other byte kept), checks that the
result reads back (every other key as it was, the written keys as generated) and replaces the file atomically; a
byte-order mark is kept.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from ur3hanoi.errors import TableError, printable
from ur3hanoi.io.atomic import locked_output
from ur3hanoi.io.reading import read_input_bytes
from ur3hanoi.tables.file import WHAT, LabFile, check_key, parse_lab_file, warn_confusable
from ur3hanoi.tables.format import ANGLE_DECIMALS
from ur3hanoi.tables.sections import Sections


def write_sections(path: str | Path, sections: Sections, inputs: Sequence[str | Path] = ()) -> str:
    """Write ``sections`` into the lab table file ``path`` (created or updated in place; see the module docstring).

    Args:
        path: the lab table file (a symlink is written through to its target).
        sections: the keys to write.
        inputs: files the output must not be (the calibration the keys were generated from).

    Returns:
        The text written.

    Raises:
        TableError: ``sections.key`` is not a table key, or the existing file is not valid YAML or its top level is
            not a mapping, or the result would not read back.
        OutputError: ``path`` cannot be written (an input file, a directory, a device, no space...).

    In both cases the file is left byte-identical.
    """
    key = sections.key
    check_key(key)
    with locked_output(path, inputs=inputs) as out:
        raw = read_input_bytes(out.path, what=WHAT, error=TableError, source=out.shown) if out.exists() else None
        from ur3hanoi.io.yaml_loader import BOM
        from ur3hanoi.tables.splice import splice_yaml

        old = parse_lab_file(raw, out.shown) if raw is not None else LabFile(data={}, text="", sha256="")
        # A look-alike of a key written is warned about (one of a key present, by parse_lab_file already).
        warn_confusable(old.data, out.shown, [k for k in sections.text if k not in old.data])
        try:
            text = splice_yaml(old.text, sections.text, sections.headers, sections.values)
        except TableError as exc:
            raise TableError(f"{printable(out.shown)}: cannot write '{key}': {exc}; file left unchanged") from None
        _check_read_back(text, old, sections, out.shown)
        out.write(BOM + text if old.bom else text)
    return text


def _same(a: Any, b: Any) -> bool:
    """Equal parsed YAML values, NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_same(a[k], b[k]) for k in a)
    return bool(a == b) and type(a) is type(b)


_READ_BACK_TOL = 10.0 ** -ANGLE_DECIMALS
"""[rad or m] How far a written number may read back from its value: one step of the last decimal written."""


def _reads_back(got: Any, want: Any) -> bool:
    """``got`` (parsed YAML) holds the numbers of ``want`` (nested lists of floats, or an array) in its shape, each
    within :data:`_READ_BACK_TOL`."""
    if hasattr(want, "tolist"):  # an array
        want = want.tolist()
    if isinstance(want, list | tuple):
        return (isinstance(got, list) and len(got) == len(want)
                and all(_reads_back(g, w) for g, w in zip(got, want, strict=True)))
    return (isinstance(got, int | float) and not isinstance(got, bool)
            and abs(float(got) - float(want)) <= _READ_BACK_TOL)


def _check_read_back(text: str, old: LabFile, sections: Sections, shown: str) -> None:
    """Refuse to write anything that does not read back: every other key as it was, ours as generated. A text
    equal to the file's own reads back as the file did (it is not parsed again)."""
    def refuse(why: str) -> TableError:
        return TableError(f"{printable(shown)}: cannot write '{sections.key}' in place ({why}); file left unchanged")

    if text == old.text:
        new_data: Any = old.data
    else:
        from ur3hanoi.io.yaml_loader import reparse_yaml

        try:  # the old text passed the strict loader: its nesting is bounded, libyaml may read it back
            new_data = reparse_yaml(text, shown, what=WHAT, error=TableError)
        except TableError as exc:
            raise refuse(str(exc).removeprefix(f"{printable(shown)}: ")) from None
    if not isinstance(new_data, dict):
        raise refuse("the result is not a mapping")
    added = [k for k in new_data if k not in old.data and k not in sections.text]
    if added:
        raise refuse(f"a key {printable(repr(added[0]), 60)} would appear")
    for k, v in old.data.items():
        if k not in sections.text and (k not in new_data or not _same(new_data[k], v)):
            raise refuse(f"key {printable(k, 60)!r} would change")
    for k, v in sections.values.items():
        if not _reads_back(new_data.get(k), v):
            raise refuse(f"'{k}' does not read back")


__all__ = ["write_sections"]
