"""Caps on every input file, so a careless or hostile file is refused quickly with one line.

The shipped files are far below every cap (a lab table is about 5 KiB, 4 levels deep, 400 nodes, no aliases).
"""

from __future__ import annotations

MAX_FILE_BYTES = 1 << 20
"""Largest input file [bytes] (1 MiB)."""

MAX_DEPTH = 32
"""Deepest nesting of YAML collections (a lab table needs 4)."""

MAX_NODES = 20_000
"""Most YAML nodes in a document, every alias counted as the nodes it expands to (stops "billion laughs").
A full 10 x 20 lab table has about 3,000, 1,000 taught points about 16,000."""

MAX_ALIASES = 100
"""Most aliases (``*name``) in a document."""

MAX_INT_DIGITS = 30
"""Longest integer literal [digits]; longer ones are refused before Python converts them."""

MAX_LIST_ITEMS = 10_000
"""Longest list a schema accepts unless it says otherwise."""

MAX_TOWERS = 10
"""Most towers of a station's grid (``grid.towers``)."""

MAX_HEIGHTS = 20
"""Most heights of a station's grid (``grid.heights``)."""
