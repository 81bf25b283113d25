#!/usr/bin/env bash
# Headless MuJoCo rendering (MUJOCO_GL=egl: --video/--frames and the notebooks) needs Mesa's EGL and GL drivers.
# Installs them with apt-get when missing and we are root; otherwise says what to install. Python packages are
# not installed here (see requirements.lock).
set -euo pipefail
missing=()
ldconfig -p | grep -q 'libEGL.so.1 ' || missing+=(libegl1)
ldconfig -p | grep -q 'libEGL_mesa.so.0 ' || missing+=(libegl-mesa0)
[ -e /usr/lib/x86_64-linux-gnu/dri ] || [ -e /usr/lib/aarch64-linux-gnu/dri ] || missing+=(libgl1-mesa-dri)
[ ${#missing[@]} -eq 0 ] && exit 0
if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
  echo "installing headless rendering libraries: ${missing[*]}" >&2
  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
else
  echo "warning: headless rendering needs: ${missing[*]} (e.g. sudo apt-get install ${missing[*]})" >&2
fi
