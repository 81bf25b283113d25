"""Reading input files: only regular files, never blocking, never without bound."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from ur3hanoi.errors import InputError, TableError
from ur3hanoi.io.limits import MAX_FILE_BYTES
from ur3hanoi.io.reading import read_input_bytes


def test_regular_file_is_read(tmp_path: Path) -> None:
    path = tmp_path / "f.yaml"
    path.write_bytes(b"x" * MAX_FILE_BYTES)
    assert read_input_bytes(path, what="test file") == b"x" * MAX_FILE_BYTES


@pytest.mark.parametrize(
    ("kind", "match"),
    [
        ("directory", "is a directory, not a test file"),
        ("fifo", r"is a FIFO \(named pipe\), not a test file"),
        ("dev-zero", "is a device, not a test file"),
        ("symlink-to-dev-zero", "is a device, not a test file"),
        ("too-large", f"is {MAX_FILE_BYTES + 1} bytes, more than a test file can be"),
        ("missing", r"cannot read the test file \(No such file or directory\); hint"),
        ("nul-in-path", "the path contains a NUL character"),
        ("dangling-symlink", r"cannot read the test file \(No such file or directory\)"),
    ],
)
def test_unreadable_inputs_are_refused_without_blocking(tmp_path: Path, kind: str, match: str) -> None:
    path: str | Path = tmp_path / "f.yaml"
    if kind == "directory":
        path = tmp_path
    elif kind == "fifo":
        os.mkfifo(path)  # a blocking open would hang here: no writer ever comes
    elif kind == "dev-zero":
        path = "/dev/zero"
    elif kind == "symlink-to-dev-zero":
        Path(path).symlink_to("/dev/zero")
    elif kind == "too-large":
        Path(path).write_bytes(b"#" * (MAX_FILE_BYTES + 1))
    elif kind == "nul-in-path":
        path = f"{tmp_path}/a\0b.yaml"
    elif kind == "dangling-symlink":
        Path(path).symlink_to(tmp_path / "nowhere.yaml")
    with pytest.raises(TableError, match=match) as info:
        read_input_bytes(path, what="test file", error=TableError, missing_hint="; hint")
    assert isinstance(info.value, InputError) and "\n" not in str(info.value)


def test_source_names_the_file_in_messages(tmp_path: Path) -> None:
    with pytest.raises(InputError, match=r"^my label: cannot read"):
        read_input_bytes(tmp_path / "nope", what="test file", source="my label")
