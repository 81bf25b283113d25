"""The strict YAML loader: duplicate keys, alias bombs, deep nesting, huge numbers and foreign encodings refused."""

from __future__ import annotations

import codecs
import hashlib
from pathlib import Path

import pytest

from ur3hanoi.errors import CalibrationError, InputError
from ur3hanoi.io.limits import MAX_ALIASES, MAX_DEPTH, MAX_INT_DIGITS, MAX_NODES
from ur3hanoi.io.yaml_loader import load_yaml_file, parse_yaml


def _laughs(levels: int) -> str:
    lines = ["a0: &a0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]"]
    for i in range(1, levels + 1):
        lines.append(f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * 9)}]")
    return "\n".join(lines) + "\n"


HOSTILE = {
    "billion-laughs": (_laughs(9), f"refused as a YAML file: more than {MAX_NODES} nodes"),
    "many-aliases": ("a: &a 1\nb: [" + ", ".join(["*a"] * (MAX_ALIASES + 1)) + "]\n",
                     f"more than {MAX_ALIASES} aliases"),
    "recursive-alias": ("a: &a [1, *a]\n", r"alias \*a is used inside its own anchor"),
    "deep-flow": ("[" * 100_000 + "]" * 100_000, f"nested deeper than {MAX_DEPTH} levels"),
    "deep-block": ("".join(" " * i + f"k{i}:\n" for i in range(200)) + " " * 200 + "x\n",
                   f"nested deeper than {MAX_DEPTH} levels"),
    "400-digit-int": ("a: " + "9" * 400 + "\n", f"integer longer than {MAX_INT_DIGITS} digits"),
    "5000-digit-int": ("a: " + "1" * 5000 + "\n", f"integer longer than {MAX_INT_DIGITS} digits"),
    "many-nodes": ("[" + ", ".join(["0"] * (MAX_NODES + 1)) + "]", f"more than {MAX_NODES} nodes"),
    "duplicate-key": ("a: 1\nb: 2\n'a': 3\n", r"duplicate key 'a' \(first given on line 1\) \(line 3, column 1\)"),
    "duplicate-nested": ("x:\n  k: 1\n  \"k\": 2\n", "duplicate key 'k'"),
    "duplicate-int-float": ("{1: a, 1.0: b}", "duplicate key 1.0"),
    "python-object": ("!!python/object/apply:os.system ['echo hi']\n", "could not determine a constructor"),
    "bad-date": ("a: 2025-13-45\n", "not valid YAML: month must be in 1..12"),
    "unhashable-key": ("? [1, 2]\n: x\n", "found unhashable key"),
    "two-documents": ("a: 1\n---\nb: 2\n", "expected a single document in the stream: but found another document"),
    "undefined-alias": ("a: *nope\n", "found undefined alias 'nope'"),
    "nul-character": ("a: 1\x00\n", "unacceptable character #x0000"),
    "tab-indent": ("a:\n\t- 1\n", "found character '\\\\t' that cannot start any token"),
}


@pytest.mark.parametrize("case", sorted(HOSTILE))
def test_hostile_yaml_is_refused_in_one_line(case: str) -> None:
    text, match = HOSTILE[case]
    with pytest.raises(InputError, match=match) as info:
        parse_yaml(text, "evil.yaml")
    msg = str(info.value)
    assert msg.startswith("evil.yaml: ") and "\n" not in msg and len(msg) < 300


def test_merge_keys_and_a_few_aliases_still_work() -> None:
    data = parse_yaml("base: &b {x: 1, y: 2}\nother:\n  <<: *b\n  y: 3\nlist: [*b, *b]\n", "ok.yaml")
    assert data["other"] == {"x": 1, "y": 3}
    assert data["list"] == [{"x": 1, "y": 2}] * 2


def test_error_class_is_the_file_kinds() -> None:
    with pytest.raises(CalibrationError, match="duplicate key"):
        parse_yaml("a: 1\na: 2\n", "cal.yaml", error=CalibrationError)


@pytest.mark.parametrize(
    ("raw", "match"),
    [
        ("a: 1\n".encode("utf-16"), "is UTF-16 text: save the test file as UTF-8"),
        ("a: 1\n".encode("utf-16-be"), "unacceptable character #x0000"),
        ("a: caf\xe9\n".encode("latin-1"), r"is not UTF-8 text \(byte 0xe9 at offset 6\)"),
    ],
    ids=["utf16-bom", "utf16-no-bom", "latin1"],
)
def test_non_utf8_files_are_refused(tmp_path: Path, raw: bytes, match: str) -> None:
    path = tmp_path / "f.yaml"
    path.write_bytes(raw)
    with pytest.raises(InputError, match=match):
        load_yaml_file(path, what="test file")


def test_utf8_with_bom_loads_and_hashes_the_bytes(tmp_path: Path) -> None:
    path = tmp_path / "f.yaml"
    raw = codecs.BOM_UTF8 + "name: café\n".encode()
    path.write_bytes(raw)
    doc = load_yaml_file(path, what="test file")
    assert doc.data == {"name": "café"}
    assert doc.sha256 == hashlib.sha256(raw).hexdigest()


def test_empty_file_is_none(tmp_path: Path) -> None:
    path = tmp_path / "f.yaml"
    path.write_text("# only a comment\n")
    assert load_yaml_file(path, what="test file").data is None
