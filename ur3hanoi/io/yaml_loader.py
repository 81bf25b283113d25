"""The one YAML loader of ur3hanoi: strict, safe, and bounded.

On top of PyYAML's ``SafeLoader`` (no Python objects) it refuses, with one line naming the file and the line:

- a key given twice in one mapping (PyYAML would silently keep the last one; ``sim_pos`` and ``"sim_pos"`` are the
  same key);
- "billion laughs" alias bombs: at most :data:`~ur3hanoi.io.limits.MAX_ALIASES` aliases, and at most
  :data:`~ur3hanoi.io.limits.MAX_NODES` nodes with every alias counted as the nodes it expands to; an alias inside
  its own anchor (a recursive document) is refused too;
- nesting deeper than :data:`~ur3hanoi.io.limits.MAX_DEPTH` (instead of a ``RecursionError``);
- integers longer than :data:`~ur3hanoi.io.limits.MAX_INT_DIGITS` digits;
- anything but UTF-8 text (UTF-16 or Latin-1 files), and files that are not regular or too large
  (see :mod:`ur3hanoi.io.reading`).

YAML 1.1 (what PyYAML implements) reads a few plain scalars as something other than what they look like:
``010`` is the octal number 8, ``1:30`` is 90 (base 60), ``1_5.7`` is 15.7 (underscores are digit separators, so
``1_000`` is 1000; YAML 1.2 reads both as text), and unquoted ``on``/``off``/``yes``/``no`` are booleans. The
loader keeps such a scalar as a :class:`Yaml11Reading` (its source text, the YAML 1.1 value and what that value
means) instead of the silent value, and the schema validator (:mod:`ur3hanoi.io.schema`) refuses it wherever a
number or a name is expected, quoting the source text and how to write it (``pose: "on"``). Where a file holds
free-form data (a student's own keys in a lab table), it stays as it is.
"""

from __future__ import annotations

import codecs
import hashlib
from pathlib import Path
from typing import Any, NamedTuple

import yaml
from yaml.constructor import ConstructorError, SafeConstructor
from yaml.nodes import MappingNode, Node, ScalarNode

from ur3hanoi.errors import InputError, printable, quote
from ur3hanoi.io.limits import MAX_ALIASES, MAX_DEPTH, MAX_INT_DIGITS, MAX_NODES
from ur3hanoi.io.reading import read_input_bytes
from ur3hanoi.io.yaml11 import OCTAL, Yaml11Reading

_MERGE_TAG = "tag:yaml.org,2002:merge"


_YAML11_BOOLS = frozenset({"yes", "no", "on", "off"})
_SEPARATORS = "(its underscores dropped as digit separators)"


def _octal(text: str) -> bool:
    """``010``, ``-0_17``: an integer with a leading zero, read by YAML 1.1 as octal (``07`` reads as 7 either
    way and is kept)."""
    digits = text.lstrip("+-").replace("_", "")
    return len(digits) > 1 and digits[0] == "0" and digits.isdigit()


def _plain(node: ScalarNode) -> bool:
    """An unquoted scalar: PyYAML's Python parser gives it the style None, its libyaml parser ``""``."""
    return not node.style


class YamlLimitError(yaml.MarkedYAMLError):
    """A document exceeds one of the limits of :mod:`ur3hanoi.io.limits`."""


class StrictConstructor(SafeConstructor):
    """``SafeConstructor`` that refuses duplicate keys and huge integers and keeps YAML 1.1 surprises as
    :class:`Yaml11Reading` (the construction half of :class:`StrictLoader`, shared with the libyaml read-back of
    :func:`reparse_yaml`)."""

    def construct_mapping(self, node: MappingNode, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, MappingNode):
            first: dict[Any, Any] = {}
            for key_node, _ in node.value:
                if key_node.tag == _MERGE_TAG:
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    seen = first.get(key)
                except TypeError:  # unhashable: the base class reports it
                    continue
                if seen is not None:
                    raise ConstructorError(None, None, f"duplicate key {quote(key)} (first given on line "
                                                       f"{seen.line + 1})", key_node.start_mark)
                first[key] = key_node.start_mark
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node: ScalarNode) -> int | Yaml11Reading:  # type: ignore[override]
        text = str(node.value)
        if sum(c.isalnum() for c in text) > MAX_INT_DIGITS:
            raise YamlLimitError(problem=f"integer longer than {MAX_INT_DIGITS} digits", problem_mark=node.start_mark)
        value: int = super().construct_yaml_int(node)
        if _plain(node) and _octal(text) and int(text.replace("_", ""), 10) != value:
            return Yaml11Reading(text, value, f"{OCTAL} {value}", node.start_mark.line + 1)
        if _plain(node) and ":" in text:
            return Yaml11Reading(text, value, f"{value} (a base-60 number)", node.start_mark.line + 1)
        if _plain(node) and "_" in text:
            return Yaml11Reading(text, value, f"{value} {_SEPARATORS}", node.start_mark.line + 1)
        return value

    def construct_yaml_float(self, node: ScalarNode) -> float | Yaml11Reading:  # type: ignore[override]
        value: float = super().construct_yaml_float(node)
        text = str(node.value)
        if _plain(node) and ":" in text:
            return Yaml11Reading(text, value, f"{value:g} (a base-60 number)", node.start_mark.line + 1)
        if _plain(node) and "_" in text:
            return Yaml11Reading(text, value, f"{value!r} {_SEPARATORS}", node.start_mark.line + 1)
        return value

    def construct_yaml_bool(self, node: ScalarNode) -> bool | Yaml11Reading:  # type: ignore[override]
        value: bool = super().construct_yaml_bool(node)
        if _plain(node) and str(node.value).lower() in _YAML11_BOOLS:
            return Yaml11Reading(str(node.value), value, f"the boolean {str(value).lower()}", node.start_mark.line + 1)
        return value


def _use_strict_scalars(loader: Any) -> None:
    """Register :class:`StrictConstructor`'s integer, float and boolean constructors on ``loader`` (a loader class
    looks its constructors up in its own table)."""
    loader.add_constructor("tag:yaml.org,2002:int", StrictConstructor.construct_yaml_int)
    loader.add_constructor("tag:yaml.org,2002:float", StrictConstructor.construct_yaml_float)
    loader.add_constructor("tag:yaml.org,2002:bool", StrictConstructor.construct_yaml_bool)


class StrictLoader(StrictConstructor, yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses duplicate keys, alias bombs, deep nesting and huge integers (composed in
    Python, so that every node is counted before the next is read)."""

    def __init__(self, stream: str) -> None:
        super().__init__(stream)
        self._depth = 0
        self._nodes = 0
        self._aliases = 0
        self._anchored_sizes: dict[int, int] = {}

    def _count(self, n: int, mark: Any) -> None:
        self._nodes += n
        if self._nodes > MAX_NODES:
            raise YamlLimitError(problem=f"more than {MAX_NODES} nodes (aliases counted expanded)",
                                 problem_mark=mark)

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        event = self.peek_event()
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                raise YamlLimitError(problem=f"more than {MAX_ALIASES} aliases", problem_mark=event.start_mark)
            node = super().compose_node(parent, index)
            size = self._anchored_sizes.get(id(node))
            if size is None:
                raise YamlLimitError(problem=f"alias *{printable(event.anchor, 40)} is used inside its own anchor "
                                             "(a recursive document)", problem_mark=event.start_mark)
            self._count(size, event.start_mark)
            return node
        self._depth += 1
        if self._depth > MAX_DEPTH:
            raise YamlLimitError(problem=f"nested deeper than {MAX_DEPTH} levels", problem_mark=event.start_mark)
        before = self._nodes
        node = super().compose_node(parent, index)
        self._depth -= 1
        self._count(1, event.start_mark)
        if event.anchor is not None:
            self._anchored_sizes[id(node)] = self._nodes - before
        return node


_use_strict_scalars(StrictLoader)


BOM = "\ufeff"
"""The byte-order mark a UTF-8 file may start with (not part of :attr:`YamlFile.text`)."""


class YamlFile(NamedTuple):
    """A loaded YAML file: the parsed ``data``, the decoded ``text`` (without a byte-order mark), the sha256 of the
    file's bytes, and whether it started with a UTF-8 byte-order mark (``bom``). (A NamedTuple: this module must not
    import dataclasses, see :class:`~ur3hanoi.io.yaml11.Yaml11Reading`.)"""

    data: Any
    text: str
    sha256: str
    bom: bool = False


def _describe(exc: yaml.YAMLError) -> str:
    if isinstance(exc, yaml.MarkedYAMLError):
        problem = printable(": ".join(p for p in (exc.context, exc.problem) if p) or "syntax error", 160)
        mark = exc.problem_mark or exc.context_mark
        where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
        return f"{problem}{where}"
    return printable(str(exc).splitlines()[0] if str(exc) else type(exc).__name__, 120)


def parse_yaml(text: str, source: str, *, what: str = "YAML file", error: type[InputError] = InputError) -> Any:
    """Parse one YAML document strictly (see the module docstring); ``None`` for an empty document.

    Raises:
        error: the text is not valid YAML or exceeds a limit; the message names ``source`` and the line.
    """
    try:
        return yaml.load(text, Loader=StrictLoader)  # StrictLoader derives from SafeLoader
    except YamlLimitError as exc:
        raise error.file(source, f"refused as a {what}: {_describe(exc)}") from None
    except yaml.YAMLError as exc:
        raise error.file(source, f"not valid YAML: {_describe(exc)}") from None
    except (ValueError, OverflowError, RecursionError) as exc:  # e.g. a timestamp with month 13
        raise error.file(source, f"not valid YAML: {printable(exc, 120)}") from None


if yaml.__with_libyaml__:
    from yaml._yaml import CParser

    class _LibyamlReparse(CParser, StrictConstructor, yaml.resolver.Resolver):
        """libyaml's parser and composer with :class:`StrictConstructor` (PyYAML's ``CSafeLoader`` with the strict
        construction): it composes in C, so the limits are checked on the composed graph (:func:`_check_graph`)."""

        def __init__(self, stream: str) -> None:
            CParser.__init__(self, stream)
            StrictConstructor.__init__(self)
            yaml.resolver.Resolver.__init__(self)

    _use_strict_scalars(_LibyamlReparse)


def _children(node: Node) -> list[Node]:
    if isinstance(node, MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


def _check_graph(root: Node) -> None:
    """The limits :class:`StrictLoader` checks while composing, checked on a composed graph (depth-first, in
    document order): at most ``MAX_DEPTH`` levels, ``MAX_ALIASES`` aliases (a node met again after its anchor) and
    ``MAX_NODES`` nodes with every alias counted as the nodes it expands to; an alias inside its own anchor (a
    cycle) is refused."""
    sizes: dict[int, int] = {}  # id -> expanded size, of every finished node
    on_path = {id(root)}
    aliases = 0
    root_children = _children(root)
    stack = [(root, 1, root_children, iter(root_children))]
    while stack:
        node, depth, children, rest = stack[-1]
        child = next(rest, None)
        if child is None:
            stack.pop()
            on_path.discard(id(node))
            sizes[id(node)] = 1 + sum(sizes[id(c)] for c in children)
            if sizes[id(node)] > MAX_NODES:
                raise YamlLimitError(problem=f"more than {MAX_NODES} nodes (aliases counted expanded)",
                                     problem_mark=node.start_mark)
        elif id(child) in on_path:
            raise YamlLimitError(problem="an alias is used inside its own anchor (a recursive document)",
                                 problem_mark=child.start_mark)
        elif id(child) in sizes:
            aliases += 1
            if aliases > MAX_ALIASES:
                raise YamlLimitError(problem=f"more than {MAX_ALIASES} aliases", problem_mark=child.start_mark)
        elif depth >= MAX_DEPTH:
            raise YamlLimitError(problem=f"nested deeper than {MAX_DEPTH} levels", problem_mark=child.start_mark)
        else:
            on_path.add(id(child))
            grandchildren = _children(child)
            stack.append((child, depth + 1, grandchildren, iter(grandchildren)))


def reparse_yaml(text: str, source: str, *, what: str = "YAML file", error: type[InputError] = InputError) -> Any:
    """:func:`parse_yaml` of ``text``, read by libyaml's C parser when PyYAML has it (an order of magnitude faster):
    the same data, or :func:`parse_yaml`'s error.

    For a text made from a document :func:`parse_yaml` accepted (the read-back of a key spliced into a lab file):
    libyaml composes recursively in C, so its nesting must already be known to be bounded. The limits, duplicate
    keys and YAML 1.1 readings are checked as :func:`parse_yaml` checks them; on anything libyaml or these checks
    refuse, :func:`parse_yaml` reads the text and words the error.
    """
    if not yaml.__with_libyaml__:
        return parse_yaml(text, source, what=what, error=error)
    loader = _LibyamlReparse(text)
    try:
        node = loader.get_single_node()
        if node is None:
            return None
        _check_graph(node)
        return loader.construct_document(node)
    except (yaml.YAMLError, ValueError, OverflowError, RecursionError):
        return parse_yaml(text, source, what=what, error=error)
    finally:
        loader.dispose()


def decode_utf8(raw: bytes, source: str, *, what: str = "YAML file", error: type[InputError] = InputError) -> str:
    """``raw`` as text: UTF-8 (a UTF-8 byte-order mark is allowed), anything else is refused."""
    if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
        raise error.file(source, f"is UTF-16 text: save the {what} as UTF-8")
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error.file(source, f"is not UTF-8 text (byte 0x{raw[exc.start]:02x} at offset {exc.start}): save "
                                 f"the {what} as UTF-8") from None


def load_yaml_file(path: str | Path, *, what: str, error: type[InputError] = InputError,
                   source: str | None = None, missing_hint: str = "") -> YamlFile:
    """Read and parse the YAML file ``path`` (see :func:`ur3hanoi.io.reading.read_input_bytes`, :func:`parse_yaml`).

    Args:
        path: the file.
        what: its kind, for messages ("calibration file").
        error: the file kind's exception class.
        source: how the file is named in messages (default ``str(path)``).
        missing_hint: appended to the message when the file does not exist.
    """
    source = str(path) if source is None else source
    raw = read_input_bytes(path, what=what, error=error, source=source, missing_hint=missing_hint)
    return parse_yaml_bytes(raw, source, what=what, error=error)


def parse_yaml_bytes(raw: bytes, source: str, *, what: str = "YAML file",
                     error: type[InputError] = InputError) -> YamlFile:
    """A YAML file from the bytes ``raw`` read from it (:func:`decode_utf8`, then :func:`parse_yaml`)."""
    text = decode_utf8(raw, source, what=what, error=error)
    data = parse_yaml(text, source, what=what, error=error)
    return YamlFile(data=data, text=text, sha256=hashlib.sha256(raw).hexdigest(), bom=raw.startswith(codecs.BOM_UTF8))
