"""Finding Debian's ROS from the venv, and `ur3hanoi ros-env`: a separate Python imports ur3_driver.msg."""

from __future__ import annotations

import os
import shlex
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.ros_support import requires_ros, run, ur3hanoi_cmd
from ur3hanoi.interface.ros1.env import ROS_PYTHON_DIR, env_lines

MD5 = ["c8890f8a9e9a6dc32b97081f6283bc11", "86ad7fb432e90c4fcc2fa98c89466a9b", "a4b7d373885d48c37baffd91ce2f1c38"]
CHECK = ("import sys, rospy, numpy, yaml; from ur3_driver.msg import command, position, gripper_input; "
         "print(command._md5sum, position._md5sum, gripper_input._md5sum); print(numpy.__file__); "
         "print(yaml.__file__); print(rospy.__file__)")


def test_env_lines_are_shell_exports():
    lines = env_lines(Path("/tmp/a b"), "http://127.0.0.1:11411")
    assert lines == ["export ROS_MASTER_URI=http://127.0.0.1:11411",
                     "export PYTHONPATH='/tmp/a b'${PYTHONPATH:+:$PYTHONPATH}"]


def test_missing_ros_names_the_debian_packages(tmp_path):
    # A fresh interpreter with the ROS folder pointed elsewhere: rospy cannot be found.
    code = ("import pathlib, ur3hanoi.interface.ros1.env as e; e.ROS_PYTHON_DIR = pathlib.Path('/nonexistent'); "
            "e.ensure_ros_python()")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                            env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert result.returncode != 0
    last = result.stderr.strip().splitlines()[-1]
    assert "RosUnavailableError: ROS 1 Python modules rospy, genpy, genmsg, std_msgs are not importable" in last
    assert "python3-rospy python3-genpy python3-std-msgs" in last


@requires_ros
def test_ros_python_is_appended_after_the_venv(tmp_path):
    code = ("import sys, ur3hanoi.interface.ros1.env as e; e.ensure_ros_python(); import rospy, numpy, yaml; "
            "print(sys.path.index(str(e.ROS_PYTHON_DIR)), len(sys.path)); print(numpy.__file__, yaml.__file__)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                         check=True).stdout.splitlines()
    index, n = map(int, out[0].split())
    assert index == n - 1
    assert str(ROS_PYTHON_DIR) not in out[1]  # the venv's numpy and PyYAML win


@requires_ros
@pytest.mark.parametrize("python", [sys.executable, "/usr/bin/python3"])
def test_ros_env_lets_a_separate_python_import_the_messages(tmp_path, python):
    if not Path(python).exists():
        pytest.skip(f"no {python}")
    folder = tmp_path / "env"
    result = run(ur3hanoi_cmd("ros-env", "--dir", str(folder), "--master", "http://127.0.0.1:11999"),
                 dict(os.environ), 60)
    assert result.returncode == 0, result.stderr
    assert result.stdout.splitlines() == env_lines(folder, "http://127.0.0.1:11999")
    code = CHECK if python == sys.executable else CHECK.replace(", numpy, yaml", "").split("; print(numpy")[0]
    shell = f'eval "$({shlex.join(ur3hanoi_cmd("ros-env", "--dir", str(folder)))})" && ' \
            f'echo "$ROS_MASTER_URI" && exec {shlex.quote(python)} -c {shlex.quote(code)}'
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "ROS_MASTER_URI")}
    out = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, timeout=60, env=env)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "http://localhost:11311"
    assert lines[1].split() == MD5
    if python == sys.executable:
        assert str(ROS_PYTHON_DIR) not in lines[2] and str(ROS_PYTHON_DIR) not in lines[3]
        assert lines[4].startswith(str(ROS_PYTHON_DIR))


@requires_ros
def test_sitecustomize_runs_the_next_one_on_the_path(tmp_path):
    folder = tmp_path / "env"
    assert run(ur3hanoi_cmd("ros-env", "--dir", str(folder)), dict(os.environ), 60).returncode == 0
    other = tmp_path / "other"
    other.mkdir()
    (other / "sitecustomize.py").write_text("import builtins\nbuiltins.ur3hanoi_chained = True\n")
    code = "import builtins, rospy; print(getattr(builtins, 'ur3hanoi_chained', False))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=True,
                         env=dict(os.environ, PYTHONPATH=f"{folder}:{other}"))
    assert out.stdout.strip() == "True"


@requires_ros
@pytest.mark.parametrize("python", [sys.executable, "/usr/bin/python3"])
def test_ros_env_applied_twice_is_harmless(tmp_path, python):
    """Twice the same folder, then a second folder, then a foreign sitecustomize: every Python still starts (it
    raised RecursionError), the messages import and the foreign sitecustomize runs exactly once."""
    if not Path(python).exists():
        pytest.skip(f"no {python}")
    other = tmp_path / "other"
    other.mkdir()
    (other / "sitecustomize.py").write_text("import builtins\n"
                                            "builtins.ur3hanoi_runs = getattr(builtins, 'ur3hanoi_runs', 0) + 1\n")
    evals = " && ".join(f'eval "$({shlex.join(ur3hanoi_cmd("ros-env", "--dir", str(tmp_path / d)))})"'
                        for d in ("a", "a", "b"))
    code = ("import builtins, rospy; from ur3_driver.msg import command; "
            "print(command._md5sum, getattr(builtins, 'ur3hanoi_runs', 0))")
    env = {k: v for k, v in os.environ.items() if k != "ROS_MASTER_URI"}
    env["PYTHONPATH"] = str(other)
    shell = f"{evals} && echo \"$PYTHONPATH\" && exec {shlex.quote(python)} -c {shlex.quote(code)}"
    out = subprocess.run(["bash", "-c", shell], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "Error in sitecustomize" not in out.stderr and "RecursionError" not in out.stderr, out.stderr[-2000:]
    lines = out.stdout.splitlines()
    assert lines[0].split(":") == [str(tmp_path / "b"), str(tmp_path / "a"), str(tmp_path / "a"), str(other)]
    assert lines[1].split() == [MD5[0], "1"]


def test_missing_driver_packages_are_named(tmp_path):
    code = ("import ur3hanoi.interface.ros1.env as e; e._DRIVER_MODULES = ('actionlib', 'no_such_module_msgs'); "
            "e.ensure_driver_python()")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60,
                            env={k: v for k, v in os.environ.items() if k != "PYTHONPATH"})
    assert result.returncode != 0
    last = result.stderr.strip().splitlines()[-1]
    assert "no_such_module_msgs (for the UR driver's interface) are not importable" in last
    assert "python3-actionlib python3-actionlib-msgs python3-trajectory-msgs python3-sensor-msgs" in last
