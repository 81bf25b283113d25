"""ur3hanoi.opengl: the OpenGL platform is chosen by trying each candidate in a child process (the display's, else
EGL, else OSMesa), a user's MUJOCO_GL is kept, the choice is made once per process and handed on to the processes it
starts, and with no platform the error names what was tried and what provides it."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from tests.support import REPO
from tests.support.opengl_support import without_opengl
from ur3hanoi.errors import SimulationError
from ur3hanoi.opengl import EGL, GLFW, MUJOCO_GL, OSMESA, VERIFIED, Choice, choose, render_failed

NO_DISPLAY = "no display (DISPLAY and WAYLAND_DISPLAY are unset)"


def _headless(**extra: str) -> dict[str, str]:
    """This process's environment with no display, no MUJOCO_GL and nothing verified, plus ``extra``."""
    drop = (MUJOCO_GL, VERIFIED, "DISPLAY", "WAYLAND_DISPLAY")
    return {**{k: v for k, v in os.environ.items() if k not in drop}, **extra}


def test_without_a_display_or_a_setting_the_first_headless_platform_that_works_is_chosen() -> None:
    choice = choose(_headless())
    assert choice.chosen and choice.platform in (EGL, OSMESA)
    assert choice.passed_over[0] == "no display"
    assert choice.describe().startswith(f"{choice.platform.title} (MUJOCO_GL unset, no display")


def test_a_display_that_does_not_answer_is_passed_over_without_a_warning(capfd: pytest.CaptureFixture[str]) -> None:
    """DISPLAY names an X server that is not there (a stale ssh setting): GLFW fails in the child, quietly."""
    choice = choose(_headless(DISPLAY=":9731"))
    assert choice.chosen and choice.platform in (EGL, OSMESA)
    assert choice.passed_over[0] == "the display failed"
    assert capfd.readouterr().err == ""  # GLFW's warnings stayed in the child's pipe


def test_the_users_setting_is_tried_alone_and_kept() -> None:
    working = choose(_headless()).platform.name
    choice = choose(_headless(MUJOCO_GL=working))
    assert choice == Choice(choice.platform, chosen=False) and choice.platform.name == working
    assert choice.describe() == f"{choice.platform.title} (MUJOCO_GL={working})"


@pytest.mark.parametrize(("value", "says"), [
    ("glfw", "MUJOCO_GL='glfw' (set in the environment): X11: The DISPLAY environment variable is missing; the "
             "display's OpenGL (GLFW) needs a display"),
    ("vulkan", "MUJOCO_GL='vulkan' (set in the environment): RuntimeError: invalid value for environment variable "
               "MUJOCO_GL: vulkan; expected glfw (a display"),
])
def test_a_users_setting_that_fails_is_one_line_naming_it(value: str, says: str) -> None:
    with pytest.raises(SimulationError) as err:
        choose(_headless(MUJOCO_GL=value))
    message = str(err.value)
    assert says in message and "\n" not in message, message
    assert message.endswith("or unset MUJOCO_GL to let ur3hanoi choose")


def test_a_platform_verified_by_the_parent_is_not_tried_again(monkeypatch: pytest.MonkeyPatch) -> None:
    import ur3hanoi.opengl

    def no_probe(*_args: object, **_kwargs: object) -> str:
        raise AssertionError("probed again")

    monkeypatch.setattr(ur3hanoi.opengl, "probe", no_probe)
    assert choose(_headless(MUJOCO_GL="egl", UR3HANOI_OPENGL="egl chosen")) == Choice(EGL, chosen=True)
    assert choose(_headless(MUJOCO_GL="osmesa", UR3HANOI_OPENGL="osmesa set")) == Choice(OSMESA, chosen=False)
    with pytest.raises(AssertionError, match="probed again"):  # another platform than the verified one is tried
        choose(_headless(MUJOCO_GL="osmesa", UR3HANOI_OPENGL="egl chosen"))


_ONCE = """
import json, os, subprocess, sys
import ur3hanoi.opengl as gl
calls = []
real = gl.probe
gl.probe = lambda *a, **k: calls.append(a[0]) or real(*a, **k)
first, second = gl.use_platform(), gl.use_platform()
child = subprocess.run([sys.executable, "-c", "import ur3hanoi.opengl as gl\\n"
                        "gl.probe = lambda *a, **k: 1 / 0\\nprint(gl.use_platform().platform.name)"],
                       capture_output=True, text=True)
print(json.dumps({"calls": calls, "same": first == second, "env": [os.environ.get(gl.MUJOCO_GL),
                  os.environ.get(gl.VERIFIED)], "child": child.stdout.strip(), "child_err": child.stderr}))
"""


def test_the_choice_is_made_once_per_process_and_handed_to_its_children() -> None:
    proc = subprocess.run([sys.executable, "-c", _ONCE], env=_headless(), capture_output=True, text=True,
                          cwd=REPO, timeout=120, check=False)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    out = json.loads(proc.stdout)
    name = out["env"][0]
    assert name in ("egl", "osmesa") and out["env"][1] == f"{name} chosen"
    assert out["calls"] == (["egl"] if name == "egl" else ["egl", "osmesa"])
    assert out["same"] and out["child"] == name, out["child_err"]  # the child used it without a probe


def test_with_no_platform_the_error_names_each_one_tried_and_what_provides_it() -> None:
    """On a machine without EGL, OSMesa or a display (made by tests/support/opengl_support.py): first, the hiding
    really hides (each probe fails there, and at least one works here); then the one line."""
    made = without_opengl()
    if isinstance(made, str):
        pytest.skip(made)
    prefix, env = made
    code = ("import json\nfrom ur3hanoi.opengl import choose, probe\n"
            "out = {p: probe(p) for p in ('egl', 'osmesa', 'glfw')}\n"
            "try:\n    choose()\nexcept Exception as exc:\n    out['error'] = str(exc)\nprint(json.dumps(out))")
    proc = subprocess.run([*prefix, sys.executable, "-c", code], env=env, capture_output=True, text=True, cwd=REPO,
                          timeout=180, check=False)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    out = json.loads(proc.stdout)
    assert all(out[p] for p in ("egl", "osmesa", "glfw")), out  # every platform hidden
    assert "libEGL" in out["egl"] and "libOSMesa" in out["osmesa"], out
    assert choose(_headless()).platform in (EGL, OSMESA)  # and one renders outside
    error = out["error"]
    assert error.startswith("offscreen rendering found no OpenGL platform that works (MUJOCO_GL unset): tried ")
    assert f"{GLFW.title}: {NO_DISPLAY}" in error
    assert f"EGL: {out['egl']} (needs Debian packages libegl1, libegl-mesa0, libgl1-mesa-dri)" in error
    assert f"OSMesa: {out['osmesa']} (needs Debian package libosmesa6)" in error
    assert "\n" not in error


_UNCHOSEN = """
import mujoco
from ur3hanoi.opengl import offscreen_renderer, use_platform
use_platform()  # too late for this process: MuJoCo has bound GLFW
try:
    offscreen_renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 16, 16)
except Exception as exc:
    print(type(exc).__name__, exc)
"""


def test_a_script_that_imports_mujoco_before_choosing_gets_one_line_and_no_warning() -> None:
    """MuJoCo imported with MUJOCO_GL unset and no display binds GLFW, which cannot work, whatever is chosen after:
    the renderer's failure is one line saying what to do, and GLFW's warnings go into it, not onto stderr."""
    proc = subprocess.run([sys.executable, "-c", _UNCHOSEN], env=_headless(), capture_output=True, text=True,
                          cwd=REPO, timeout=120, check=False)
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert proc.stdout == ("SimulationError offscreen rendering is unavailable: X11: The DISPLAY environment variable "
                           "is missing; MuJoCo was imported with MUJOCO_GL unset (GLFW, which needs a display): call "
                           "ur3hanoi.opengl.use_platform() before importing MuJoCo, or set MUJOCO_GL\n")


def test_a_renderer_that_fails_after_the_choice_says_which_setting_failed() -> None:
    assert render_failed("no context", {"MUJOCO_GL": "osmesa"}) == (
        "offscreen rendering with MUJOCO_GL='osmesa' failed: no context; OSMesa needs Debian package libosmesa6")
