#!/usr/bin/env bash
# System packages the project needs outside its virtual environment, installed with apt-get when missing and we
# are root; otherwise says what to install. Python packages from PyPI are not installed here (requirements.lock).
#  - Headless MuJoCo rendering (--video/--frames and notebook 04 choose EGL without a display, ur3hanoi/opengl.py):
#    Mesa's EGL and GL drivers.
#  - ROS 1 for `ur3hanoi ros-station` / `ros-solve` and their tests: Debian's roscore and pure-Python rospy,
#    genpy and std_msgs (about 40 s); for the UR driver's interface (--driver ur) also actionlib, actionlib_msgs,
#    trajectory_msgs and sensor_msgs. ur3hanoi.interface.ros1 appends /usr/lib/python3/dist-packages to the venv's path.
#  - Debian's chromium: the replay page's test opens it headless with the network off (tests/replay/test_page.py).
set -euo pipefail
missing=()
ldconfig -p | grep -q 'libEGL.so.1 ' || missing+=(libegl1)
ldconfig -p | grep -q 'libEGL_mesa.so.0 ' || missing+=(libegl-mesa0)
[ -e /usr/lib/x86_64-linux-gnu/dri ] || [ -e /usr/lib/aarch64-linux-gnu/dri ] || missing+=(libgl1-mesa-dri)
command -v roscore >/dev/null || missing+=(ros-core)
# ROS 2 interop tests (tests/test_ros2_*.py): a private network namespace (ip from iproute2, unshare) and a C/C++
# toolchain with cmake to build the course's ur3e_mrc_msgs for the throwaway rclpy environment.
command -v ip >/dev/null || missing+=(iproute2)
command -v cmake >/dev/null || missing+=(cmake)
command -v g++ >/dev/null || missing+=(g++)
command -v make >/dev/null || missing+=(make)
command -v chromium >/dev/null || missing+=(chromium)
for pkg in rospy genpy std_msgs actionlib actionlib_msgs trajectory_msgs sensor_msgs; do
  [ -e "/usr/lib/python3/dist-packages/$pkg/__init__.py" ] || missing+=("python3-${pkg//_/-}")
done
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "installing system packages: ${missing[*]}" >&2
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
else
  echo "warning: missing system packages: ${missing[*]} (e.g. sudo apt-get install ${missing[*]})" >&2
fi
