"""The ROS 1 packages UR's own clients import (``ros-env --driver ur``): written by genpy from the vendored texts,
importable by a plain ``python3`` with the folder on its path, every service's md5sum the one other projects'
generated code carries for the same Noetic text (so a client built from the official packages interoperates)."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from tests.support.ros_support import requires_ros

pytestmark = requires_ros

UPSTREAM_MD5 = {  # found in independently generated code of the same texts (rosnodejs, rosserial, Elixir bindings)
    "controller_manager_msgs/SwitchController": "b29a7abc673b2c54c14b54e50f8d06a5",
    "controller_manager_msgs/ListControllers": "1341feb2e63fa791f855565d0da950d8",
    "controller_manager_msgs/LoadController": "647e5c54b8d6468952d8d31f1efe96c0",
    "std_srvs/Trigger": "937c9679a518e3a18d831e57125ea522",
    "ur_dashboard_msgs/IsProgramRunning": "290f0cb02c3a44353957f0a92f954209",
}

_PROBE = """
import json
from controller_manager_msgs.srv import SwitchController, ListControllers, LoadController, SwitchControllerRequest
from cartesian_control_msgs.msg import FollowCartesianTrajectoryAction, CartesianTrajectoryPoint
from control_msgs.msg import FollowJointTrajectoryAction
from std_srvs.srv import Trigger
from ur_dashboard_msgs.srv import IsProgramRunning
print(json.dumps({c._type: c._md5sum for c in (SwitchController, ListControllers, LoadController, Trigger,
                                                IsProgramRunning, FollowJointTrajectoryAction)}
                 | {"STRICT": SwitchControllerRequest.STRICT}))
"""


def test_the_written_packages_import_and_carry_the_upstream_md5sums(tmp_path):
    from ur3hanoi.interface.ros1.env import ROS_PYTHON_DIR
    from ur3hanoi.interface.ros1.ur_packages import service_classes, write_ur_packages

    written = write_ur_packages(tmp_path)
    assert (tmp_path / "controller_manager_msgs" / "srv" / "_SwitchController.py") in written
    env = dict(os.environ, PYTHONPATH=f"{tmp_path}:{ROS_PYTHON_DIR}")
    out = subprocess.run([sys.executable, "-c", _PROBE], env=env, capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    seen = json.loads(out.stdout)
    assert seen.pop("STRICT") == 2
    assert seen == {**UPSTREAM_MD5, "control_msgs/FollowJointTrajectoryAction": "bc4f9b743838566551c0390c65f1a248"}
    # The station's own classes (generated in memory) answer clients of the same sums.
    station = service_classes()
    assert {t: station[t]._md5sum for t in UPSTREAM_MD5} == UPSTREAM_MD5
