"""Declarative schemas for the YAML input files, and the one validator that checks a parsed document.

A schema says, for every field, its type and valid range; :func:`validate` walks a parsed document against it
and raises the file kind's :class:`~ur3hanoi.errors.InputError` naming the file, the field path
(``grid.tower_origins[2][1]``), the bad value (shortened) and what is allowed. Unknown keys are errors with the
nearest valid key suggested (``robot.base_rpy`` -> did you mean ``robot.base_rpy_deg``?). Numbers must be finite
(no ``.nan``/``.inf``); booleans are not numbers. Cross-field rules (a ``_deg``/``_rad`` pair, a count matching a
list) stay with the file kind's parser, after this check.
"""

from __future__ import annotations

import difflib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from ur3hanoi.errors import MISSING, InputError, printable, quote
from ur3hanoi.io.limits import MAX_LIST_ITEMS
from ur3hanoi.io.number import Number as Number  # re-exported: a schema field's range is a Number
from ur3hanoi.io.yaml11 import OCTAL, Yaml11Reading


@dataclass(frozen=True)
class Vector:
    """A list of exactly ``n`` numbers, each checked by ``item``."""

    n: int
    item: Number

    def expected(self) -> str:
        return f"a list of {self.n} numbers, each {self.item.expected()}"


@dataclass(frozen=True)
class Choice:
    """One of a few strings."""

    options: tuple[str, ...]

    def expected(self) -> str:
        return f"one of {', '.join(self.options)}"


@dataclass(frozen=True)
class Text:
    """A non-empty single-line string of at most ``max_len`` characters."""

    max_len: int = 100

    def expected(self) -> str:
        return f"a non-empty single-line string of at most {self.max_len} characters"

    def accepts(self, value: Any) -> bool:
        return isinstance(value, str) and bool(value.strip()) and len(value) <= self.max_len and value.isprintable()


@dataclass(frozen=True)
class ListOf:
    """A list of ``min_items`` .. ``max_items`` items, each checked by ``item``."""

    item: Spec
    min_items: int = 1
    max_items: int = MAX_LIST_ITEMS
    what: str = "items"

    def expected(self) -> str:
        if self.min_items == self.max_items:
            return f"a list of exactly {self.min_items} {self.what}"
        return f"a list of {self.min_items}..{self.max_items} {self.what}"


@dataclass(frozen=True)
class Nullable:
    """``null`` (a value left out on purpose, e.g. an entry not recorded) or a value checked by ``item``."""

    item: Spec

    def expected(self) -> str:
        return f"{self.item.expected()}, or null"


@dataclass(frozen=True)
class Field:
    """One key of a :class:`Record`."""

    spec: Spec
    required: bool = True


@dataclass(frozen=True)
class Record:
    """A mapping with the given keys (optional ones may be absent). Any other key is an error, unless ``others``:
    then other keys are the file owner's and hold anything."""

    fields: Mapping[str, Field] = field(default_factory=dict)
    others: bool = False

    def expected(self) -> str:
        return f"a mapping with keys {', '.join(self.fields)}"


Spec = Number | Vector | Choice | Text | ListOf | Nullable | Record


def _join(path: str, key: str) -> str:
    return f"{path}.{key}" if path else key


def suggest(key: object, valid: list[str]) -> str | None:
    """The valid key nearest to ``key`` (difflib ratio >= 0.6; ties go to the earlier key: ``_deg`` before
    ``_rad``), or None."""
    text = str(key)[:200]
    best, best_score = None, 0.6
    for name in valid:
        matcher = difflib.SequenceMatcher(None, text, name)
        if matcher.real_quick_ratio() >= best_score and matcher.quick_ratio() >= best_score:
            score = matcher.ratio()
            if score > best_score or (best is None and score >= best_score):
                best, best_score = name, score
    return best


def describe_type(value: Any) -> str:
    """``"a list"``, ``"a str"``, ``"an empty document"`` (for ``None``): what a value is, for messages."""
    if value is None:
        return "an empty document"
    name = type(value).__name__
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name}"


class _Validator:
    def __init__(self, source: str, error: type[InputError]) -> None:
        self.source = source
        self.error = error

    def fail(self, path: str, value: Any, allowed: str) -> InputError:
        if not path:
            return self.error.file(self.source, f"expected {allowed}, got {describe_type(value)}")
        return self.error.invalid(self.source, path, value, allowed)

    def ambiguous(self, path: str, value: Yaml11Reading, spec: Spec) -> InputError:
        """``010``, ``1:30``, ``1_5.7``, ``on`` where the schema expects a number or a name: quote the source, say
        how to write it."""
        while isinstance(spec, Nullable):
            spec = spec.item
        said = f"YAML 1.1 reads {value.text} as {value.meaning}"
        if isinstance(spec, Text | Choice):
            leaf = path.rsplit(".", 1)[-1] if path and not path.endswith("]") else ""
            how = f"{leaf}: \"{value.text}\"" if leaf else f"\"{value.text}\""
            allowed = f"{said}; for the text write it in quotes ({how}); expected {spec.expected()}"
        elif isinstance(spec, Number) and not isinstance(value.value, bool) and not value.meaning.startswith(OCTAL):
            allowed = f"{said}; write the number itself ({value.value}) if that is what you mean; expected " \
                      f"{spec.expected()}"
        elif isinstance(spec, Number) and not isinstance(value.value, bool):
            decimal = int(value.text.replace("_", ""))
            allowed = f"{said}; write {decimal} or {value.value}, whichever you mean, without the leading zero; " \
                      f"expected {spec.expected()}"
        else:
            allowed = f"{said}; expected {spec.expected()}"
        where = f"{printable(self.source)}: field '{printable(path, 60)}'" if path else printable(self.source)
        return self.error(f"{where} = {printable(value.text, 60)} (line {value.line}) is ambiguous: {allowed}",
                          source=self.source, field=path, value=value, allowed=allowed)

    def check(self, value: Any, spec: Spec, path: str) -> None:
        if isinstance(value, Yaml11Reading):
            raise self.ambiguous(path, value, spec)
        if isinstance(spec, Number):
            if not spec.accepts(value):
                raise self.fail(path, value, spec.expected())
        elif isinstance(spec, Vector):
            if not isinstance(value, list) or len(value) != spec.n:
                raise self.fail(path, value, spec.expected())
            for i, v in enumerate(value):
                self.check(v, spec.item, f"{path}[{i}]")
        elif isinstance(spec, Choice):
            if not isinstance(value, str) or value not in spec.options:
                raise self.fail(path, value, spec.expected())
        elif isinstance(spec, Text):
            if not spec.accepts(value):
                raise self.fail(path, value, spec.expected())
        elif isinstance(spec, Nullable):
            if isinstance(spec.item, Number) and value is not None and not spec.item.accepts(value):
                raise self.fail(path, value, spec.expected())  # a leaf: say that null is allowed too
            if value is not None:
                self.check(value, spec.item, path)
        elif isinstance(spec, ListOf):
            if not isinstance(value, list) or not spec.min_items <= len(value) <= spec.max_items:
                raise self.fail(path, value, spec.expected())
            for i, v in enumerate(value):
                self.check(v, spec.item, f"{path}[{i}]")
        else:
            self.record(value, spec, path)

    def record(self, value: Any, spec: Record, path: str) -> None:
        if not isinstance(value, dict):
            raise self.fail(path, value, spec.expected())
        names = list(spec.fields)
        for key in value:
            if not spec.others and (not isinstance(key, str) or key not in spec.fields):
                self.unknown(key, names, path)
        for name, f in spec.fields.items():
            if name in value:
                self.check(value[name], f.spec, _join(path, name))
            elif f.required:
                raise self.error.invalid(self.source, _join(path, name), MISSING, f.spec.expected())

    def unknown(self, key: Any, names: list[str], path: str) -> None:
        shown = printable(key, 60) if isinstance(key, str) else quote(key)
        name = _join(path, shown)
        near = suggest(key, names)
        where = f"{printable(self.source)}: field '{name}' is unknown"
        if near is not None:
            allowed = f"did you mean '{_join(path, near)}'?"
        else:
            allowed = f"expected one of {', '.join(_join(path, n) for n in names)}"
        raise self.error(f"{where}: {allowed}", source=self.source, field=name, value=key, allowed=allowed)


def validate(data: Any, schema: Spec, source: str, error: type[InputError] = InputError, path: str = "") -> None:
    """Check the parsed document ``data`` (or the value at field ``path`` of one) against ``schema``.

    Raises:
        error: the first problem found, naming ``source``, the field path, the value and what is allowed.
    """
    _Validator(source, error).check(data, schema, path)
