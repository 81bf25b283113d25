"""The user's cache: content keys, hits, corrupt entries rebuilt, an unwritable cache tolerated, two processes racing
on an empty cache (with the entry the clearance checks keep: the robot's collision geometry)."""

from __future__ import annotations

import base64
import json
import subprocess
from pathlib import Path

import pytest

import ur3hanoi.io.cache
from tests.support.cache_race import start_racer
from ur3hanoi.io.cache import cache_dir, content_key, entry_path, load, store

PAYLOAD = bytes(range(256)) * 1000  # every byte value, 256 kB


@pytest.fixture(autouse=True)
def private_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    return tmp_path / "xdg" / "ur3hanoi"


def test_cache_dir_is_the_users(private_cache: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    assert cache_dir() == private_cache
    monkeypatch.setenv("XDG_CACHE_HOME", "")
    monkeypatch.setenv("HOME", "/home/student")
    assert cache_dir() == Path("/home/student/.cache/ur3hanoi")
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert cache_dir() == Path("/home/student/.cache/ur3hanoi")


def test_key_is_the_content(monkeypatch: pytest.MonkeyPatch) -> None:
    key = content_key("demo", [b"station", b"urdf"])
    assert key == content_key("demo", [b"station", b"urdf"])
    assert len(key) == 64 and int(key, 16) >= 0
    others = [content_key("demo", [b"station", b"urdF"]),  # one byte of one input
              content_key("demo", [b"statio", b"nurdf"]),  # same bytes, other split
              content_key("demo", [b"station"]),
              content_key("other", [b"station", b"urdf"])]
    monkeypatch.setattr(ur3hanoi.io.cache, "__version__", "99.0")
    others.append(content_key("demo", [b"station", b"urdf"]))  # another ur3hanoi version
    assert len({key, *others}) == 6


def test_store_then_hit(private_cache: Path) -> None:
    key = content_key("demo", [b"x"])
    assert load("demo", key) is None
    assert store("demo", key, PAYLOAD)
    assert load("demo", key) == PAYLOAD
    assert sorted(p.name for p in private_cache.iterdir()) == [f"demo-{key}.cache"]  # no temporary or lock file
    assert load("demo", content_key("demo", [b"y"])) is None  # another content: a miss


def _corrupt(path: Path, how: str) -> None:
    raw = path.read_bytes()
    head, body = raw.split(b"\n", 1)
    header = json.loads(head)
    if how == "truncated":
        path.write_bytes(raw[: len(raw) // 2])
    elif how == "payload byte changed":  # still valid base64, one payload byte differs: the digest catches it
        payload = bytearray(base64.b64decode(body))
        payload[1000] ^= 0x01
        path.write_bytes(head + b"\n" + base64.b64encode(bytes(payload)) + b"\n")
    elif how == "not base64":
        path.write_bytes(head + b"\n" + b"@@@" + body[3:])
    elif how == "header garbage":
        path.write_bytes(b"\x00\xff{not json\n" + body)
    elif how == "foreign key":  # a whole, valid entry of another key under this name
        header["key"] = "0" * 64
        path.write_bytes(json.dumps(header).encode() + b"\n" + body)
    elif how == "other format":
        header["format"] = 0
        path.write_bytes(json.dumps(header).encode() + b"\n" + body)
    elif how == "empty":
        path.write_bytes(b"")
    elif how == "directory":
        path.unlink()
        path.mkdir()
    else:
        raise AssertionError(how)


@pytest.mark.parametrize("how", ["truncated", "payload byte changed", "not base64", "header garbage", "foreign key",
                                 "other format", "empty"])
def test_corrupt_entry_is_ignored_and_rebuilt(how: str) -> None:
    key = content_key("demo", [b"x"])
    store("demo", key, PAYLOAD)
    _corrupt(entry_path("demo", key), how)
    assert load("demo", key) is None
    assert store("demo", key, PAYLOAD)  # rewritten
    assert load("demo", key) == PAYLOAD


def test_unusable_cache_costs_only_the_rebuild(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    key = content_key("demo", [b"x"])
    store("demo", key, PAYLOAD)
    _corrupt(entry_path("demo", key), "directory")  # the entry's path is a directory: unreadable, unwritable
    assert load("demo", key) is None
    assert store("demo", key, PAYLOAD) is False
    not_a_dir = tmp_path / "file"
    not_a_dir.write_text("")
    monkeypatch.setenv("XDG_CACHE_HOME", str(not_a_dir))  # the cache folder cannot be created
    assert load("demo", key) is None
    assert store("demo", key, PAYLOAD) is False


_RACE_BODY = """
    import numpy as np
    from ur3hanoi.plan import CollisionScene
    scene = CollisionScene(station, 3)
    scene.place_blocks({0: (0, 0), 1: (1, 0), 2: (2, 0)})
    q = np.array([2.0, -1.2, 1.3, -1.7, -1.57, 0.4])
    d = scene.distances(q, [(g, scene.table) for g in scene.robot_geoms] + [(scene.cup, b) for b in scene.blocks])
    print(cache_events[0][0], hashlib.sha256(d.tobytes()).hexdigest())
"""


def _racer(ready: Path, hold_s: float, n_racers: int) -> subprocess.Popen[str]:
    return start_racer(_RACE_BODY, ready, hold_s, n_racers)


def test_two_processes_racing_on_an_empty_cache(private_cache: Path, tmp_path: Path) -> None:
    """Both miss and build at once, and both write; each gets a correct scene, one whole entry remains and nothing
    else (no temporary or lock file); a third process then hits it and computes the same distances."""
    procs = [_racer(tmp_path / "ready", 1.0, 2) for _ in range(2)]  # both wait until both have imported Pinocchio
    outs = [p.communicate(timeout=120) for p in procs]
    assert [p.returncode for p in procs] == [0, 0], [err for _, err in outs]
    (status_a, digest_a), (status_b, digest_b) = (out.split() for out, _ in outs)
    assert status_a == status_b == "miss"
    entries = sorted(private_cache.iterdir())
    assert [p.suffix for p in entries] == [".cache"], entries
    third = _racer(tmp_path / "ready-third", 0.0, 1)
    out, err = third.communicate(timeout=120)
    assert third.returncode == 0, err
    assert out.split() == ["hit", digest_a] and digest_a == digest_b
    assert sorted(private_cache.iterdir()) == entries
