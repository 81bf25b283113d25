"""The course's ur3_driver messages from genpy: md5sums, wire format, the importable package (no master needed)."""

from __future__ import annotations

import io
import subprocess
from pathlib import Path

import pytest

from tests.support.ros_support import requires_ros
from ur3hanoi.interface.ros1.msgs import MESSAGES, load_messages, message_source, write_message_package

pytestmark = requires_ros

# As published in the course's generated message code (issue 12, ../shared/lab/ros-interface.md).
COURSE_MD5 = {"command": "c8890f8a9e9a6dc32b97081f6283bc11", "position": "86ad7fb432e90c4fcc2fa98c89466a9b",
              "gripper_input": "a4b7d373885d48c37baffd91ce2f1c38"}


def test_classes_carry_the_courses_md5sums_and_types():
    msgs = load_messages()
    for name, md5 in COURSE_MD5.items():
        cls = getattr(msgs, name)
        assert cls._md5sum == md5
        assert cls._type == f"ur3_driver/{name}"


def test_genpy_dynamic_agrees_on_the_md5sums():
    import genpy.dynamic  # type: ignore[import-not-found]  # importable after load_messages() found ROS

    load_messages()
    for spec in MESSAGES:
        cls = genpy.dynamic.generate_dynamic(spec.type, spec.definition)[spec.type]
        assert cls._md5sum == COURSE_MD5[spec.name]


def test_wire_format_round_trip():
    msgs = load_messages()
    cmd = msgs.command(destination=[0.5, -1.0, 1.5, -2.0, 2.5, -3.0], v=4.0, a=4.0, io_0=True)
    buf = io.BytesIO()
    cmd.serialize(buf)
    data = buf.getvalue()
    assert len(data) == 4 + 6 * 8 + 8 + 8 + 1  # uint32 array length, 6 doubles, v, a, bool
    back = msgs.command()
    back.deserialize(data)
    assert list(back.destination) == list(cmd.destination) and (back.v, back.a, back.io_0) == (4.0, 4.0, True)


def test_written_package_imports_in_debians_python(tmp_path):
    python = Path("/usr/bin/python3")
    if not python.exists():
        pytest.skip("no /usr/bin/python3")
    files = write_message_package(tmp_path)
    assert {p.relative_to(tmp_path).as_posix() for p in files} == {
        "ur3_driver/__init__.py", "ur3_driver/msg/__init__.py", "ur3_driver/msg/_command.py",
        "ur3_driver/msg/_position.py", "ur3_driver/msg/_gripper_input.py"}
    assert (tmp_path / "ur3_driver/msg/_command.py").read_text() == message_source(MESSAGES[0])
    code = "from ur3_driver.msg import command, position, gripper_input as g; " \
           "print(command._md5sum, position._md5sum, g._md5sum)"
    out = subprocess.run([str(python), "-c", code], env={"PYTHONPATH": str(tmp_path)}, capture_output=True,
                         text=True, timeout=60, check=True).stdout.split()
    assert out == [COURSE_MD5["command"], COURSE_MD5["position"], COURSE_MD5["gripper_input"]]
