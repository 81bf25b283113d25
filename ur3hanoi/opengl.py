"""The OpenGL platform MuJoCo renders offscreen with (``MUJOCO_GL``), chosen once per process before MuJoCo is
imported: the one home of that choice, used by every command that renders (``solve --video/--frames``, the stations'
rendering process) and by the test suite.

MuJoCo binds its platform when ``mujoco`` is imported: ``glfw`` (its default) needs a display, ``egl`` and ``osmesa``
render without one. A platform that fails can leave the process unusable for the others (``import mujoco`` itself
raises with ``MUJOCO_GL=egl`` and no libEGL; GLFW and PyOpenGL keep their first state), and its libraries complain
on the terminal (GLFW's warnings). So :func:`use_platform` tries each candidate of :data:`PLATFORMS` in a short child
process that renders one 16x16 frame, its output kept from the terminal: the display's (GLFW) when ``DISPLAY`` or
``WAYLAND_DISPLAY`` is set, then EGL, then OSMesa. The first that works goes into ``MUJOCO_GL`` for this process and
every process it starts. A ``MUJOCO_GL`` the user set is tried alone and never replaced.

Cost: one child process per candidate tried (one where the first works), about 0.5 s of CPU, most of it importing
MuJoCo once more (``bench/bench_opengl.py``); paid only when a command is about to render, at most once per process.
The result is handed on through the environment (:data:`VERIFIED`): a process ur3hanoi starts (a rendering worker,
the stations' rendering process, a command the test suite runs) finds the platform already tried and pays nothing.

This is a loose module, not part of :mod:`ur3hanoi.sim`, because it must run before MuJoCo is imported, and
importing anything of ``ur3hanoi.sim`` imports MuJoCo.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Mapping, MutableMapping
from typing import NamedTuple

from ur3hanoi.errors import SimulationError, printable, quote

MUJOCO_GL = "MUJOCO_GL"
"""The environment variable MuJoCo reads when it is imported."""

VERIFIED = "UR3HANOI_OPENGL"
"""Set with ``MUJOCO_GL`` by :func:`use_platform` for the processes this one starts: ``"<platform> chosen"`` or
``"<platform> set"`` (the user's ``MUJOCO_GL``), meaning that ``MUJOCO_GL=<platform>`` renders here. A child whose
``MUJOCO_GL`` is that platform uses it without trying it again."""

PROBE_TIMEOUT_S = 60.0
"""Longest a probe may take [s] (typically 0.3-1 s: importing MuJoCo, one GL context, one frame)."""


class Platform(NamedTuple):
    """One of MuJoCo's OpenGL platforms: its ``MUJOCO_GL`` value, its name in messages, what provides it."""

    name: str
    title: str
    provides: str


GLFW = Platform("glfw", "the display's OpenGL (GLFW)", "a display: an X or Wayland session (DISPLAY, WAYLAND_DISPLAY)")
EGL = Platform("egl", "EGL", "Debian packages libegl1, libegl-mesa0, libgl1-mesa-dri")
OSMESA = Platform("osmesa", "OSMesa", "Debian package libosmesa6")
PLATFORMS: tuple[Platform, ...] = (GLFW, EGL, OSMESA)
"""The candidates, in the order they are tried when ``MUJOCO_GL`` is unset (the display's only with a display)."""


class Choice(NamedTuple):
    """The platform rendering uses: ``chosen`` by ur3hanoi (``MUJOCO_GL`` was unset; ``passed_over`` says why the
    candidates before it were not used) or the user's ``MUJOCO_GL`` (``chosen`` False)."""

    platform: Platform
    chosen: bool
    passed_over: tuple[str, ...] = ()

    def describe(self) -> str:
        """E.g. ``EGL (MUJOCO_GL unset, no display)``, ``OSMesa (MUJOCO_GL=osmesa)``."""
        if not self.chosen:
            return f"{self.platform.title} ({MUJOCO_GL}={self.platform.name})"
        return f"{self.platform.title} ({', '.join((f'{MUJOCO_GL} unset', *self.passed_over))})"


def display_available(environ: Mapping[str, str] | None = None) -> str | None:
    """None when a display is set (``DISPLAY`` or ``WAYLAND_DISPLAY``), else the reason there is none."""
    env = os.environ if environ is None else environ
    if not (env.get("DISPLAY") or env.get("WAYLAND_DISPLAY")):
        return "no display (DISPLAY and WAYLAND_DISPLAY are unset)"
    return None


# Run by `python -c` in the child: renders one frame with the MUJOCO_GL it was given; prints "ok", or the reason on
# one line. Library warnings (GLFW's) are recorded, not shown: the first one is usually the reason.
_PROBE = r"""
import re, sys, warnings
warnings.simplefilter("always")
with warnings.catch_warnings(record=True) as said:
    try:
        import mujoco
        model = mujoco.MjModel.from_xml_string("<mujoco/>")
        renderer = mujoco.Renderer(model, 16, 16)
        renderer.render()
        renderer.close()
    except BaseException as exc:
        libraries = {"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}
        reason = f"{type(exc).__name__}: {exc}"
        name = sys.argv[1]
        if name in libraries:
            import ctypes
            try:
                ctypes.CDLL(libraries[name])
            except OSError as missing:
                reason = str(missing)
        if said:
            reason = re.sub(r"^\(\d+\) b?['\"](.*)['\"]$", r"\1", str(said[0].message))
        print(" ".join(reason.split()))
        sys.exit(1)
print("ok")
"""


def probe(platform: str, environ: Mapping[str, str] | None = None, timeout_s: float = PROBE_TIMEOUT_S) -> str | None:
    """Render one frame with ``MUJOCO_GL=platform`` in a child process: None if it works, else why not (one line).
    Nothing the child or its libraries print reaches the terminal."""
    from ur3hanoi.lifecycle import child_preexec

    env = {**(os.environ if environ is None else environ), MUJOCO_GL: platform}
    env.pop(VERIFIED, None)
    try:
        proc = subprocess.run([sys.executable, "-c", _PROBE, platform], env=env, stdin=subprocess.DEVNULL,
                              capture_output=True, text=True, errors="replace", timeout=timeout_s,
                              preexec_fn=child_preexec(), check=False)
    except subprocess.TimeoutExpired:
        return f"no frame within {timeout_s:g} s"
    except OSError as exc:
        return f"cannot start {sys.executable}: {exc}"
    said = proc.stdout.strip()
    if proc.returncode == 0 and said == "ok":
        return None
    if not said:  # it crashed: its last line on stderr, if any
        lines = proc.stderr.strip().splitlines()
        said = f"exit {proc.returncode}" + (f": {lines[-1]}" if lines else "")
    return printable(said, 160)


def _needs(name: str) -> str:
    known = {p.name: p for p in PLATFORMS}
    if name in known:
        return f"{known[name].title} needs {known[name].provides}"
    return "expected " + ", ".join(f"{p.name} ({p.provides})" for p in PLATFORMS)


def choose(environ: Mapping[str, str] | None = None) -> Choice:
    """The platform to render with in ``environ`` (default ``os.environ``), tried in child processes (:func:`probe`);
    changes nothing. A ``MUJOCO_GL`` already verified by the process that started this one (:data:`VERIFIED`) is
    used as it is.

    Raises:
        SimulationError: the user's ``MUJOCO_GL`` does not work, or (unset) no platform does: one line naming what
            was tried, why it failed and what provides it.
    """
    env = os.environ if environ is None else environ
    known = {p.name: p for p in PLATFORMS}
    given = env.get(MUJOCO_GL)
    if given is not None:
        name = given.strip().lower()
        verified = env.get(VERIFIED, "").split()
        if verified[:1] == [name] and name in known:
            return Choice(known[name], chosen=verified[1:] == ["chosen"])
        reason = probe(given, env)
        if reason is None:
            return Choice(known.get(name, Platform(name, f"MUJOCO_GL={name}", "")), chosen=False)
        raise SimulationError(f"offscreen rendering cannot use {MUJOCO_GL}={quote(given)} (set in the environment): "
                              f"{reason}; {_needs(name)}; or unset {MUJOCO_GL} to let ur3hanoi choose")
    tried: list[str] = []
    passed_over: list[str] = []
    for platform in PLATFORMS:
        if platform is GLFW and display_available(env) is not None:
            tried.append(f"{platform.title}: no display (DISPLAY and WAYLAND_DISPLAY unset)")
            passed_over.append("no display")
            continue
        reason = probe(platform.name, env)
        if reason is None:
            return Choice(platform, chosen=True, passed_over=tuple(passed_over))
        tried.append(f"{platform.title}: {reason} (needs {platform.provides})")
        passed_over.append(f"{platform.title} failed" if platform is not GLFW else "the display failed")
    raise SimulationError(f"offscreen rendering found no OpenGL platform that works ({MUJOCO_GL} unset): tried "
                          f"{'; '.join(tried)}; install one, or set {MUJOCO_GL}")


_CHOSEN: list[Choice | SimulationError] = []  # this process's answer, once


def use_platform(environ: MutableMapping[str, str] | None = None) -> Choice:
    """:func:`choose` once per process, its platform written to ``MUJOCO_GL`` (and :data:`VERIFIED`) in ``environ``
    (default ``os.environ``: this process and the ones it starts). Call it before MuJoCo is imported: MuJoCo reads
    ``MUJOCO_GL`` then.

    Raises:
        SimulationError: as :func:`choose` (the same error again on a second call).
    """
    env = os.environ if environ is None else environ
    if not _CHOSEN:
        try:
            _CHOSEN.append(choose(env))
        except SimulationError as exc:
            _CHOSEN.append(exc)
    answer = _CHOSEN[0]
    if isinstance(answer, SimulationError):
        raise answer
    if answer.chosen or MUJOCO_GL not in env:
        env[MUJOCO_GL] = answer.platform.name
    env[VERIFIED] = f"{answer.platform.name} {'chosen' if answer.chosen else 'set'}"
    return answer


def render_failed(reason: str, environ: Mapping[str, str] | None = None) -> str:
    """The one line when creating an offscreen renderer failed in this process (``reason``: the library's)."""
    env = os.environ if environ is None else environ
    given = env.get(MUJOCO_GL)
    if given is None:
        return (f"offscreen rendering is unavailable: {reason}; MuJoCo was imported with {MUJOCO_GL} unset (GLFW, "
                f"which needs a display): call ur3hanoi.opengl.use_platform() before importing MuJoCo, or set "
                f"{MUJOCO_GL}")
    return f"offscreen rendering with {MUJOCO_GL}={quote(given)} failed: {reason}; {_needs(given.strip().lower())}"


__all__ = ["EGL", "GLFW", "MUJOCO_GL", "OSMESA", "PLATFORMS", "PROBE_TIMEOUT_S", "VERIFIED", "Choice", "Platform",
           "choose", "display_available", "probe", "render_failed", "use_platform"]
