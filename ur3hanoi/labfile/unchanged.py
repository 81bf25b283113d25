"""Lab table files known to hold already the keys written into them, remembered in the user's cache
(:mod:`ur3hanoi.cache`), so that writing the same keys again needs neither PyYAML nor a parse.

Run again on its own output, ``ur3hanoi tables`` reads the file, finds its key's entry holding exactly the text it
would write, and writes the same bytes back: a parse for the file's layout and validity (and PyYAML's import) that
only confirms what the last run found. :func:`~ur3hanoi.labfile.update.write_sections` records such a file here
(:func:`remember`) after it read, spliced and checked it in full and the result was the file itself; a later write
of the same keys into a file of the same bytes (:func:`holds`) writes them back unparsed, which is what the full
path writes.

- **Key**: the file's bytes (by their sha256), every field of the :class:`~ur3hanoi.labfile.sections.Sections`
  written (text, provenance lines, values), the source of the ``labfile`` and ``io`` packages (the reading, splice
  and read-back check) and the PyYAML and Python versions: a file differing in one byte, other keys, another
  reader or splice is a new entry, and goes through the full read and check.
- **Entry**: empty (nothing of the file is stored); it exists or not. A corrupt or unreadable entry is no entry, and
  a cache that cannot be written only costs the parse next time.
"""

from __future__ import annotations

import hashlib
import json
import sys
from collections.abc import Iterable

from ur3hanoi import cache
from ur3hanoi.labfile.sections import Sections

UNCHANGED = "lab-file-unchanged"
"""Kind of the cache entries of this module."""

SOURCE_FOLDERS: tuple[str, ...] = ("io", "labfile")
"""The packages whose source decides what a write makes of a file: reading (``io``), splice and check
(``labfile``)."""


def _inputs(raw: bytes, sections: Sections) -> Iterable[bytes]:
    written = json.dumps([sections.key, list(sections.text.items()), list(sections.headers.items()),
                          list(sections.values.items())], allow_nan=False)
    return [hashlib.sha256(raw).digest(), written.encode(), cache.source_digest(SOURCE_FOLDERS),
            repr((cache.installed_versions(["pyyaml"]), sys.version)).encode()]


def holds(raw: bytes, sections: Sections) -> bool:
    """True when a file of bytes ``raw`` was found to hold ``sections`` already (:func:`remember`)."""
    try:
        key = cache.content_key(UNCHANGED, _inputs(raw, sections))
    except (TypeError, ValueError):  # values JSON cannot hold exactly: never remembered
        return False
    return cache.load(UNCHANGED, key) is not None


def remember(raw: bytes, sections: Sections) -> None:
    """Record that writing ``sections`` into a file of bytes ``raw`` was checked in full and gave ``raw``."""
    try:
        key = cache.content_key(UNCHANGED, _inputs(raw, sections))
    except (TypeError, ValueError):
        return
    cache.store(UNCHANGED, key, b"")


__all__ = ["SOURCE_FOLDERS", "UNCHANGED", "holds", "remember"]
