"""ur3hanoi.interface.urdriver.facts: the vendored message texts are upstream's, byte for byte (git blob ids in the
README, recomputed here), one file per distinct text, and each variant differs from its sibling only where upstream's
do; the error-code names."""

from __future__ import annotations

import hashlib
import re

from ur3hanoi.interface.urdriver.facts import MSG_TEXTS, ErrorCode, code_name, msg_text


def _git_blob(data: bytes) -> str:
    return hashlib.sha1(b"blob %d\0" % len(data) + data).hexdigest()


def _readme_rows() -> list[tuple[str, str]]:
    return re.findall(r"^\| `([^`]+)` \|.*\| ([0-9a-f]{40}) \|$", (MSG_TEXTS / "README.md").read_text(),
                      re.MULTILINE)


def test_vendored_texts_are_upstreams_blobs() -> None:
    """Every file is listed in the README with upstream's git blob id, and its bytes hash to that id."""
    rows = _readme_rows()
    files = sorted(str(p.relative_to(MSG_TEXTS)) for p in MSG_TEXTS.rglob("*") if p.is_file()
                   and p.name != "README.md")
    assert len(files) == 27 and sorted(path for path, _ in rows) == files
    for path, blob in rows:
        assert _git_blob((MSG_TEXTS / path).read_bytes()) == blob, path


def test_one_file_per_distinct_text() -> None:
    blobs = [blob for _, blob in _readme_rows()]
    assert len(set(blobs)) == len(blobs)


def test_the_ros1_joint_tolerance_differs_from_ros2s_only_in_whitespace() -> None:
    ros1, ros2 = msg_text("control_msgs", "JointTolerance-ros1.msg"), msg_text("control_msgs", "JointTolerance.msg")
    assert ros1 != ros2
    assert [line.rstrip() for line in ros1.splitlines()] == [line.rstrip() for line in ros2.splitlines()]


def test_set_io_versions_differ_in_the_pin_constants() -> None:
    current, old = msg_text("ur_msgs", "SetIO.srv"), msg_text("ur_msgs", "SetIO-1.3.srv")
    assert current.count("int8 PIN_") == 20 and "PIN_" not in old


def test_code_names() -> None:
    assert code_name(-4) == "PATH_TOLERANCE_VIOLATED (-4)"
    assert code_name(int(ErrorCode.SUCCESSFUL)) == "SUCCESSFUL (0)"
    assert code_name(7) == "error code 7"
