"""The user's cache: data derived only from input files, computed once and kept on disk, keyed by their content.

A cold ``ur3hanoi plan`` spends most of its clearance set-up reading and hulling the robot's URDF collision meshes,
which depend on nothing but the robot model and the station's tool. This module keeps such data in
:func:`cache_dir`:

- **Key**: sha256 over the ur3hanoi version, the entry's kind, and every input's bytes (a file's content, never
  its name or time stamp), so a changed station, URDF, mesh or ur3hanoi version is a new entry, never a stale one.
  Kinds that hold a library's serialization put that library's version among their inputs.
- **Entry**: ``<kind>-<key>.cache``, one header line (JSON: format, kind, key, length and sha256 of the payload)
  then the payload in base64, written by the one atomic writer (:mod:`ur3hanoi.io.atomic`: temporary file and
  rename, under a lock). A reader sees a whole entry or none; two processes that miss at once both build, and
  the second one finds the first's entry under the lock and leaves it.
- **Never an error**: an entry that is unreadable, truncated, corrupt or foreign (any header, length or digest
  mismatch) is ignored and rebuilt, and a cache folder that cannot be created or written only costs the rebuild.
  Nothing reaches a deserializer unless its digest matches what was written.
"""

from __future__ import annotations

import base64
import binascii
import contextlib
import functools
import hashlib
import json
import os
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import TypeVar

from ur3hanoi.errors import Ur3HanoiError
from ur3hanoi.version import __version__

FORMAT = 1
"""Version of the entry layout (header fields, base64 payload)."""

def cache_dir() -> Path:
    """``$XDG_CACHE_HOME/ur3hanoi`` (``~/.cache/ur3hanoi`` when XDG_CACHE_HOME is unset or empty)."""
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "ur3hanoi"


def content_key(kind: str, inputs: Iterable[bytes]) -> str:
    """sha256 (hex) of the ur3hanoi version, ``kind`` and each input, every item length-prefixed (so no two
    different input lists hash the same bytes)."""
    h = hashlib.sha256()
    for item in (__version__.encode(), kind.encode(), *inputs):
        h.update(len(item).to_bytes(8, "little"))
        h.update(item)
    return h.hexdigest()


def entry_path(kind: str, key: str) -> Path:
    """The file of one entry."""
    return cache_dir() / f"{kind}-{key}.cache"


def _header(kind: str, key: str, payload: bytes) -> dict[str, object]:
    return {"format": FORMAT, "kind": kind, "key": key, "length": len(payload),
            "sha256": hashlib.sha256(payload).hexdigest()}


def load(kind: str, key: str) -> bytes | None:
    """The payload of entry (``kind``, ``key``), or None when it is missing, unreadable or fails any check."""
    try:
        with open(entry_path(kind, key), "rb") as f:
            head = f.readline(4096)
            body = f.read()
        header = json.loads(head)
        payload = base64.b64decode(body.rstrip(b"\n"), validate=True)
    except (OSError, ValueError, binascii.Error):  # json and base64 errors are ValueErrors
        return None
    if header != _header(kind, key, payload):
        return None
    return payload


def store(kind: str, key: str, payload: bytes) -> bool:
    """Write entry (``kind``, ``key``) unless a valid one is already there; False if the cache is not writable."""
    from ur3hanoi.io.atomic import locked_output

    path = entry_path(kind, key)
    text = json.dumps(_header(kind, key, payload)) + "\n" + base64.b64encode(payload).decode("ascii") + "\n"
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with locked_output(path) as out:
            if load(kind, key) != payload:  # another process may have written it while this one was building
                out.write(text)
    except (OSError, Ur3HanoiError):
        return False
    return True


def installed_versions(names: Iterable[str]) -> tuple[tuple[str, str | None], ...]:
    """(name, version) of each installed distribution (``name`` as its ``.dist-info`` folder spells it, e.g.
    ``example_robot_data``; None when not installed): read from the folder names on ``sys.path``, the first match
    as ``importlib.metadata`` finds it, without importing it (or the library)."""
    import sys

    wanted = list(names)
    found: dict[str, str] = {}
    for entry in sys.path:
        try:
            listing = os.listdir(entry or ".")
        except OSError:
            continue
        for item in listing:
            if item.endswith(".dist-info"):
                name, _, version = item[: -len(".dist-info")].partition("-")
                if name in wanted and name not in found:
                    found[name] = version
    missing = [n for n in wanted if n not in found]
    if missing:  # another kind of install (an .egg-info, a zip): ask importlib.metadata
        import importlib.metadata

        for n in missing:
            with contextlib.suppress(importlib.metadata.PackageNotFoundError):
                found[n] = importlib.metadata.version(n)
    return tuple((n, found.get(n)) for n in wanted)


_PACKAGE = Path(__file__).resolve().parent.parent  # ur3hanoi/


def source_digest(folders: Iterable[str]) -> bytes:
    """sha256 of ur3hanoi's own modules in ``folders`` (relative to the package: ``""`` the top-level modules,
    ``"io"`` that package with its subpackages), each by its path and content: a key input for what that code
    computes. Each folder is read once per process."""
    h = hashlib.sha256()
    for folder in folders:
        h.update(_folder_digest(folder))
    return h.digest()


@functools.lru_cache(maxsize=16)
def _folder_digest(folder: str) -> bytes:
    h = hashlib.sha256()
    root = _PACKAGE / folder
    for path in sorted(root.rglob("*.py") if folder else root.glob("*.py")):
        h.update(path.relative_to(_PACKAGE).as_posix().encode() + b"\0")
        h.update(hashlib.sha256(path.read_bytes()).digest())
    return h.digest()


T = TypeVar("T")


def cached(kind: str, inputs: Iterable[bytes], build: Callable[[], T], encode: Callable[[T], bytes | None],
           decode: Callable[[bytes], T | None]) -> T:
    """The value of entry (``kind``, key of ``inputs``) through ``decode``, else ``build()``, kept through
    ``encode`` for the next process.

    ``decode`` returns None (or raises) for a payload it does not accept: such an entry is rebuilt and
    overwritten. ``encode`` returns None for a value not to be kept.
    """
    key = content_key(kind, inputs)
    payload = load(kind, key)
    if payload is not None:
        try:
            value = decode(payload)
        except Exception:  # whatever a payload that is not this kind's makes a decoder raise: rebuild it
            value = None
        if value is not None:
            return value
    value = build()
    data = encode(value)
    if data is not None:
        store(kind, key, data)
    return value
