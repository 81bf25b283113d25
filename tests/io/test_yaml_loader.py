"""The strict YAML loader: duplicate keys, alias bombs, deep nesting, huge numbers and foreign encodings refused."""

from __future__ import annotations

import codecs
import hashlib
from pathlib import Path

import pytest
import yaml

from ur3hanoi.errors import CalibrationError, InputError
from ur3hanoi.io.limits import MAX_ALIASES, MAX_DEPTH, MAX_INT_DIGITS, MAX_NODES
from ur3hanoi.io.schema import Choice, Field, ListOf, Nullable, Number, Record, Text, validate
from ur3hanoi.io.yaml_loader import Yaml11Reading, load_yaml_file, parse_yaml, reparse_yaml


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


# ------------------------------------------------------------------ YAML 1.1 readings that change a value


@pytest.mark.parametrize(
    ("text", "value", "meaning"),
    [
        ("010", 8, "the octal number 8"),
        ("-0_17", -15, "the octal number -15"),
        ("1:30", 90, "90 (a base-60 number)"),
        ("1:30.5", 90.5, "90.5 (a base-60 number)"),
        ("1_5.7", 15.7, "15.7 (its underscores dropped as digit separators)"),
        ("1_000", 1000, "1000 (its underscores dropped as digit separators)"),
        ("on", True, "the boolean true"),
        ("Off", False, "the boolean false"),
        ("YES", True, "the boolean true"),
        ("no", False, "the boolean false"),
    ],
)
def test_ambiguous_yaml11_scalars_keep_their_source_text(text: str, value: object, meaning: str) -> None:
    got = parse_yaml(f"a: {text}\nb: [1, {text}]\n", "f.yaml")
    for item in (got["a"], got["b"][1]):
        assert isinstance(item, Yaml11Reading)
        assert (item.text, item.value, item.meaning) == (text, value, meaning)
        assert repr(item) == text
    assert got["a"].line == 1 and got["b"][1].line == 2


@pytest.mark.parametrize(
    ("text", "value"),
    [("'010'", "010"), ('"on"', "on"), ("10", 10), ("0", 0), ("0x10", 16), ("true", True), ("false", False),
     ("0.5", 0.5), ("007.5", 7.5), ("-1", -1), ("'1_000'", "1_000"), ("07", 7), ("00", 0), ("'1:30'", "1:30"),
     ("y", "y")],
)
def test_unambiguous_scalars_load_as_before(text: str, value: object) -> None:
    got = parse_yaml(f"a: {text}\n", "f.yaml")["a"]
    assert got == value and type(got) is type(value)


_SCHEMA = Record({"n": Field(Number(0, 100, integer=True)), "x": Field(Number(), required=False),
                  "pose": Field(Choice(("on", "above")), required=False),
                  "name": Field(Nullable(Text()), required=False), "q": Field(ListOf(Number()), required=False)})


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("n: 010", "field 'n' = 010 (line 1) is ambiguous: YAML 1.1 reads 010 as the octal number 8; write 10 or 8, "
                   "whichever you mean, without the leading zero; expected an integer in [0, 100]"),
        ("n: 1:30", "field 'n' = 1:30 (line 1) is ambiguous: YAML 1.1 reads 1:30 as 90 (a base-60 number); write the "
                    "number itself (90) if that is what you mean"),
        ("n: 5\nx: 1:30.5", "field 'x' = 1:30.5 (line 2) is ambiguous: YAML 1.1 reads 1:30.5 as 90.5"),
        ("n: 5\nx: 1_5.7", "field 'x' = 1_5.7 (line 2) is ambiguous: YAML 1.1 reads 1_5.7 as 15.7 (its underscores "
                           "dropped as digit separators); write the number itself (15.7) if that is what you mean"),
        ("n: 1_0", "field 'n' = 1_0 (line 1) is ambiguous: YAML 1.1 reads 1_0 as 10 (its underscores dropped as "
                   "digit separators); write the number itself (10) if that is what you mean; expected an integer"),
        ("n: 5\nname: 1_5.7", "for the text write it in quotes (name: \"1_5.7\")"),
        ("n: on", "field 'n' = on (line 1) is ambiguous: YAML 1.1 reads on as the boolean true; expected an integer"),
        ("n: 5\npose: on", "field 'pose' = on (line 2) is ambiguous: YAML 1.1 reads on as the boolean true; for the "
                           "text write it in quotes (pose: \"on\"); expected one of on, above"),
        ("n: 5\nname: 010", "field 'name' = 010 (line 2) is ambiguous: YAML 1.1 reads 010 as the octal number 8; for "
                            "the text write it in quotes (name: \"010\")"),
        ("n: 5\nname: no", "(name: \"no\")"),
        ("n: 5\nq: [1, off]", "field 'q[1]' = off (line 2) is ambiguous: YAML 1.1 reads off as the boolean false"),
    ],
)
def test_ambiguous_scalars_are_refused_where_a_number_or_a_name_is_expected(text: str, message: str) -> None:
    with pytest.raises(InputError) as info:
        validate(parse_yaml(text + "\n", "f.yaml"), _SCHEMA, "f.yaml")
    assert str(info.value).startswith("f.yaml: ") and message in str(info.value) and "\n" not in str(info.value)


def test_ambiguous_scalars_are_kept_where_anything_goes() -> None:
    # A key open to its owner (a student's own keys in a lab file) holds whatever it holds, unchanged.
    data = parse_yaml("n: 5\nmine: {door: 010, lights: on}\n", "f.yaml")
    validate(data, Record({"n": Field(Number())}, others=True), "f.yaml")
    assert data["mine"] == {"door": Yaml11Reading("010", 8, "the octal number 8", 2),
                            "lights": Yaml11Reading("on", True, "the boolean true", 2)}


# --------------------------------------------------------------------------- reparse_yaml: the libyaml read-back

_SHALLOW_HOSTILE = sorted(set(HOSTILE) - {"deep-flow", "deep-block"})  # libyaml composes recursively in C
_DEPTH_EDGE = {
    "deep-flow-just-over": ("[" * (MAX_DEPTH + 1) + "]" * (MAX_DEPTH + 1), f"nested deeper than {MAX_DEPTH} levels"),
    "deep-block-just-over": ("".join(" " * i + f"k{i}:\n" for i in range(MAX_DEPTH)) + " " * MAX_DEPTH + "x\n",
                             f"nested deeper than {MAX_DEPTH} levels"),
}
_READABLE = [
    (REPO_TABLES := Path(__file__).resolve().parents[2] / "tables" / "lab2_data.yaml").read_text(encoding="utf-8"),
    "base: &b {x: 1, y: 2}\nother:\n  <<: *b\n  y: 3\nlist: [*b, *b]\n",
    "door: 010\nlights: on\ntime: 1:30\nangle: 1:30.5\nquoted: 'on'\nnull_value: ~\nempty:\n",
    "# comment\nsim_pos:\n- - [0.1, -1.2, 3.0e-3, .5, -.inf, .nan]\n  - null\nnotes: |\n  two\n  lines\n"
    "flow: {a: [1, 2], b: x}\n",
    "[" * MAX_DEPTH + "]" * MAX_DEPTH,
    "a: &a 1\nb: [" + ", ".join(["*a"] * MAX_ALIASES) + "]\n",
    "[" + ", ".join(["0"] * (MAX_NODES - 1)) + "]",
    "a: " + "9" * MAX_INT_DIGITS + "\n",
    "",
    "just a string\n",
]


def _same(a: object, b: object) -> bool:
    """Equal parsed documents, NaN equal to NaN."""
    if isinstance(a, float) and isinstance(b, float) and a != a and b != b:
        return True
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    return type(a) is type(b) and a == b


@pytest.mark.parametrize("index", range(len(_READABLE)))
def test_reparse_reads_what_the_strict_loader_reads(index: int) -> None:
    text = _READABLE[index]
    assert _same(reparse_yaml(text, "f.yaml"), parse_yaml(text, "f.yaml"))


@pytest.mark.parametrize("case", [*_SHALLOW_HOSTILE, *sorted(_DEPTH_EDGE)])
def test_reparse_refuses_what_the_strict_loader_refuses_with_its_message(case: str) -> None:
    text, match = HOSTILE.get(case) or _DEPTH_EDGE[case]
    with pytest.raises(InputError, match=match) as strict:
        parse_yaml(text, "evil.yaml")
    with pytest.raises(InputError) as fast:
        reparse_yaml(text, "evil.yaml")
    assert str(fast.value) == str(strict.value)


def test_the_graph_check_refuses_on_its_own() -> None:
    """The limits hold in the libyaml path itself, not only through the strict loader's second reading: with the
    strict loader replaced by one that accepts anything, a bomb, a cycle and deep nesting are still refused."""
    import ur3hanoi.io.yaml_loader as loader

    if not yaml.__with_libyaml__:
        pytest.skip("PyYAML without libyaml: reparse_yaml is parse_yaml")
    calls: list[str] = []

    def accept(text: str, source: str, **_: object) -> str:
        calls.append(text)
        return "accepted by the fallback"

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(loader, "parse_yaml", accept)
        for case in ("billion-laughs", "many-aliases", "recursive-alias", "many-nodes", "duplicate-key"):
            assert loader.reparse_yaml(HOSTILE[case][0], "evil.yaml") == "accepted by the fallback", case
        for text, _ in _DEPTH_EDGE.values():
            assert loader.reparse_yaml(text, "evil.yaml") == "accepted by the fallback"
        assert len(calls) == 7
        assert loader.reparse_yaml(_READABLE[1], "ok.yaml") != "accepted by the fallback"
        assert len(calls) == 7


def test_reparse_without_libyaml_is_the_strict_loader(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(yaml, "__with_libyaml__", False)
    assert _same(reparse_yaml(_READABLE[0], "f.yaml"), parse_yaml(_READABLE[0], "f.yaml"))
    with pytest.raises(InputError, match="duplicate key"):
        reparse_yaml(HOSTILE["duplicate-key"][0], "evil.yaml")
