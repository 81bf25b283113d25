"""ur3hanoi.interface.ros2.rclpy_build: the vendored texts' RIHS01 hashes (that the texts are upstream's:
tests/interface/urdriver/test_facts.py) as an independent implementation computes them (rosbags,
tests/support/rosidl_oracle.py), the environment's name follows its pins, a package's key its texts and build files;
then (marker rclpy) the built environments: every type hash the rosidl generators wrote equals rosbags', the generated
classes carry the texts' fields and constants, and ur3hanoi's own Python imports them through the lines ``ros2-env``
prints."""

from __future__ import annotations

import dataclasses
import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from rosbags.typesys import Stores

from tests.support.rclpy_support import DISTROS, PeerEnv, build_env
from tests.support.rosidl_oracle import typestore
from ur3hanoi.interface.ros2 import rclpy_build
from ur3hanoi.interface.ros2.rclpy_build import WHEELS, MsgPackage, driver_packages, env_root, package_key
from ur3hanoi.interface.ros2.rclpy_env import RclpyEnv

PINNED = {  # the rosidl generators' hashes of the vendored texts (Jazzy and Kilted wheels alike)
    "control_msgs/action/FollowJointTrajectory_Goal":
        "RIHS01_8a9060704b269608f5a340934cc26e66869dd14bdac29e2e7fd9ec8b9882d205",
    "control_msgs/action/FollowJointTrajectory_Result":
        "RIHS01_8002e99ed2c14c6faa522f2a93c26d744c5982f254f9e98ff9c6f19789bdb220",
    "control_msgs/msg/JointTolerance": "RIHS01_c254f9cece0f3b733017b6990fd46d1326e25242d6b8844398c97d9a88e7d648",
    "ur_msgs/srv/SetIO": "RIHS01_5cb0c89ea4479b2947fccdac0f92dd6636c4b7fc3a312f79ec7fb68a1daa6cd5",
    "ur_msgs/msg/IOStates": "RIHS01_7a62606d52c4b2aaa3fd3c5bc565cfda9c6fe8c2d69bbc7e3eadccde4cfc2a32",
}
PINNED_LAYOUT = {  # the action and its feedback differ between the layouts
    "jazzy": {"control_msgs/action/FollowJointTrajectory":
              "RIHS01_738ebcb7a2d7cfa42f9f1001cc99ce3a4383d1cfe508015d9be8485e4b1c66f6",
              "control_msgs/action/FollowJointTrajectory_Feedback":
              "RIHS01_3fd0aaecf71725121ae1ff7f01098a5e0da581e672be18a6b2c286cb43d96b49"},
    "kilted": {"control_msgs/action/FollowJointTrajectory":
               "RIHS01_ff29901b2693f5deb847e96084a1c2cdb26e70b7c847be21859b70a55fb29cf0",
               "control_msgs/action/FollowJointTrajectory_Feedback":
               "RIHS01_0bb018d181bdc6384dd75365480967bd1d6eaee4ef3dd597c64cd0b8bdc10867"},
}


def _texts(layout: str) -> dict[str, str]:
    """``pkg/<kind>/Name`` -> text of the packages ``ros2-env`` builds for ``layout``."""
    out = {}
    for package in driver_packages(WHEELS[layout]):
        for rel, text in package.texts.items():
            kind, file = rel.split("/")
            out[f"{package.name}/{kind}/{file.rsplit('.', 1)[0]}"] = text
    return out


@pytest.mark.parametrize("store", [Stores.ROS2_JAZZY, Stores.ROS2_KILTED])  # Humble has no type hashes
@pytest.mark.parametrize("layout", sorted(WHEELS))
def test_rosbags_computes_the_pinned_hashes(layout: str, store: Stores) -> None:
    ts = typestore(_texts(layout), store)
    for name, expected in {**PINNED, **PINNED_LAYOUT[layout]}.items():
        assert ts.hash_rihs01(name) == expected, name


def test_the_layouts_differ_only_in_the_feedback() -> None:
    jazzy, kilted = _texts("jazzy"), _texts("kilted")
    assert {k for k in jazzy if jazzy[k] != kilted[k]} == {"control_msgs/action/FollowJointTrajectory"}
    j_goal, j_result, j_feedback = jazzy["control_msgs/action/FollowJointTrajectory"].split("\n---\n")
    k_goal, k_result, k_feedback = kilted["control_msgs/action/FollowJointTrajectory"].split("\n---\n")
    assert (j_goal, j_result) == (k_goal, k_result)
    assert "int32 index" in k_feedback and "index" not in j_feedback


def test_environment_names_follow_pins_and_texts(tmp_path: Path) -> None:
    jazzy = WHEELS["jazzy"]
    root = env_root(tmp_path, jazzy, "3.11")
    assert root.name.startswith("ros2-jazzy-py3.11-")
    assert env_root(tmp_path, jazzy, "3.12") != root
    assert env_root(tmp_path, dataclasses.replace(jazzy, packages=(*jazzy.packages, "x==1")), "3.11") != root
    control = driver_packages(jazzy)[0]
    edited = MsgPackage(control.name, {**control.texts, "msg/JointTolerance.msg": "string name\n"},
                        control.dependencies)
    assert package_key(edited) != package_key(control)
    key = package_key(control)
    for template in ("_CMAKELISTS", "_PACKAGE_XML"):  # the build files made from the texts are inputs too
        with pytest.MonkeyPatch.context() as mp:
            mp.setattr(rclpy_build, template, getattr(rclpy_build, template) + "\n")
            assert package_key(control) != key, template


def test_a_missing_tool_is_one_line(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv("PATH", str(tmp_path))
    with pytest.raises(rclpy_build.RclpyUnavailableError, match=r"needs cmake on PATH \(Debian: apt-get install"):
        rclpy_build.ensure_env(tmp_path, WHEELS["jazzy"], sys.executable)
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------- the built environments

_CLASSES = """
import json, sys
from control_msgs.action import FollowJointTrajectory as F
from control_msgs.msg import JointTolerance
from ur_msgs.msg import Analog, Digital, IOStates
from ur_msgs.srv import SetIO
classes = {"control_msgs/action/FollowJointTrajectory_Goal": F.Goal,
           "control_msgs/action/FollowJointTrajectory_Result": F.Result,
           "control_msgs/action/FollowJointTrajectory_Feedback": F.Feedback,
           "control_msgs/msg/JointTolerance": JointTolerance, "ur_msgs/msg/Analog": Analog,
           "ur_msgs/msg/Digital": Digital, "ur_msgs/msg/IOStates": IOStates,
           "ur_msgs/srv/SetIO_Request": SetIO.Request, "ur_msgs/srv/SetIO_Response": SetIO.Response}
def constants(c):  # the generated metaclass keeps them in a name-mangled dict
    return next(v for k, v in vars(type(c)).items() if k.endswith("__constants"))
print(json.dumps({name: {"fields": list(c.get_fields_and_field_types()), "constants": constants(c)}
                  for name, c in classes.items()}))
"""


@pytest.fixture(scope="module", params=sorted(DISTROS))
def built(request: pytest.FixtureRequest) -> PeerEnv:
    return build_env(request.param)


def _env(peer: PeerEnv) -> RclpyEnv:
    return RclpyEnv.load(Path(peer.station["UR3HANOI_ROS2_ENV"]))


@pytest.mark.rclpy
def test_generated_hashes_equal_rosbags(built: PeerEnv) -> None:
    """Every type hash the rosidl generators wrote for control_msgs and ur_msgs (the referenced types included,
    e.g. the service events with service_msgs' ServiceEventInfo) equals rosbags' from the same texts."""
    env, ts = _env(built), typestore(_texts(built.distro))
    written = {h["type_name"]: h["hash_string"] for package in ("control_msgs", "ur_msgs")
               for f in (env.root / "msgs" / package / "share" / package).glob("*/*.json")
               for h in json.loads(f.read_text())["type_hashes"]}
    assert len(written) >= 35
    assert {name: ts.hash_rihs01(name) for name in written} == written


@pytest.mark.rclpy
def test_generated_classes_carry_the_texts_fields_and_constants(built: PeerEnv) -> None:
    out = subprocess.run([built.python, "-c", _CLASSES], env={**built.peer, "PATH": "/usr/bin:/bin"},
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    classes: dict[str, Any] = json.loads(out.stdout.strip().splitlines()[-1])
    ts = typestore(_texts(built.distro))
    for name, got in classes.items():
        consts, fields = ts.fielddefs[name]
        assert got["fields"] == [f for f, _ in fields], name
        assert got["constants"] == {c: v for c, _, v in consts}, name
    assert "PIN_DOUT1" in classes["ur_msgs/srv/SetIO_Request"]["constants"]


@pytest.mark.rclpy
def test_ur3hanoi_imports_them_through_the_printed_lines(built: PeerEnv) -> None:
    """The project's own interpreter, with only what ``eval "$(ur3hanoi ros2-env)"`` sets, imports rclpy and the
    driver's messages, keeps its own NumPy, and sees the layout of its distribution."""
    layout, env = built.distro, _env(built)
    lines = subprocess.run([sys.executable, "-m", "ur3hanoi.cli", "ros2-env", "--distro", layout, "--dir",
                            str(env.root.parent)], capture_output=True, text=True, timeout=600)
    assert lines.returncode == 0, lines.stderr
    probe = ("import numpy; from ur3hanoi.interface.ros2.rclpy_env import import_rclpy, import_interfaces; "
             "r = import_rclpy(); (a,) = import_interfaces('control_msgs.action'); "
             "print(numpy.__file__, r.__file__, "
             "'index' in a.FollowJointTrajectory.Feedback.get_fields_and_field_types())")
    out = subprocess.run(["bash", "-c", 'eval "$1"; exec "$2" -c "$3"', "-", lines.stdout, sys.executable, probe],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    numpy_file, rclpy_file, has_index = out.stdout.split()
    assert numpy_file.startswith(sys.prefix) and rclpy_file.startswith(str(env.root))
    assert has_index == str(layout == "kilted")
