"""A YAML 1.1 reading that changes what a value looks like (``010`` read as 8, ``1:30`` as 90, ``on`` as True):
kept by the loader with its source text, refused by the schema where a number or a name is expected. Its own module
(no PyYAML import), so the command-line parser can use the schema without loading YAML."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Yaml11Reading:
    """A plain scalar YAML 1.1 reads as something else than it looks: ``text`` as written, ``value`` the YAML 1.1
    reading (8 for ``010``, 90 for ``1:30``, True for ``on``), ``meaning`` that reading in words, ``line``
    1-based. Its ``repr`` is the source text, so messages quote what the file says."""

    text: str
    value: Any
    meaning: str
    line: int

    def __repr__(self) -> str:
        return self.text
