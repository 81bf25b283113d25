"""A YAML 1.1 reading that changes what a value looks like (``010`` read as 8, ``1:30`` as 90, ``on`` as True):
kept by the loader with its source text, refused by the schema where a number or a name is expected. Its own module
(no PyYAML import), so the command-line parser can use the schema without loading YAML."""

from __future__ import annotations

from typing import Any

OCTAL = "the octal number"
"""How a :class:`Yaml11Reading`'s ``meaning`` starts for an octal integer (``010``: "the octal number 8"); the
schema's advice differs for it (write 10 or 8, whichever you mean)."""


class Yaml11Reading:
    """A plain scalar YAML 1.1 reads as something else than it looks: ``text`` as written, ``value`` the YAML 1.1
    reading (8 for ``010``, 90 for ``1:30``, True for ``on``), ``meaning`` that reading in words, ``line``
    1-based. Its ``repr`` is the source text, so messages quote what the file says.

    Immutable and compared by value, like a frozen dataclass; written out because every file parse imports this
    module and ``dataclasses`` would cost a ``tables`` run 6 ms of imports. Not a tuple: a schema would take it for
    a sequence."""

    __slots__ = ("line", "meaning", "text", "value")
    text: str
    value: Any
    meaning: str
    line: int

    def __init__(self, text: str, value: Any, meaning: str, line: int) -> None:
        for name, v in (("text", text), ("value", value), ("meaning", meaning), ("line", line)):
            object.__setattr__(self, name, v)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"Yaml11Reading is immutable: cannot set {name!r}")

    def __delattr__(self, name: str) -> None:
        raise AttributeError(f"Yaml11Reading is immutable: cannot delete {name!r}")

    def _fields(self) -> tuple[str, Any, str, int]:
        return self.text, self.value, self.meaning, self.line

    def __eq__(self, other: object) -> bool:
        return type(other) is Yaml11Reading and self._fields() == other._fields()

    def __hash__(self) -> int:
        return hash(self._fields())

    def __repr__(self) -> str:
        return self.text
