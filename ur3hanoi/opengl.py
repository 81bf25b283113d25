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

Cost: one child process per candidate tried (one where the first works, or for the user's ``MUJOCO_GL``), 0.6-0.9 s
of CPU, most of it importing MuJoCo once more (``bench/bench_opengl.py``); paid only when a command is about to
render, at most once per process.
The result is handed on through the environment (:data:`VERIFIED`): a process ur3hanoi starts (a rendering worker,
the stations' rendering process, a command the test suite runs) finds the platform already tried and pays nothing.

This is a loose module, not part of :mod:`ur3hanoi.sim`, because it must run before MuJoCo is imported, and
importing anything of ``ur3hanoi.sim`` imports MuJoCo.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from collections.abc import Mapping, MutableMapping
from pathlib import Path
from typing import TYPE_CHECKING, NamedTuple

from ur3hanoi.errors import SimulationError, printable, quote

if TYPE_CHECKING:
    import warnings

    import mujoco

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


_GLFW_ERROR = re.compile(r"\((\d+)\) b?(['\"])(.*)\2")


def _said(message: str) -> str:
    """A library's message on one line; GLFW's ``(65550) b'X11: ...'`` as ``X11: ...``."""
    message = " ".join(message.split())
    glfw = _GLFW_ERROR.fullmatch(message)
    return glfw.group(3) if glfw else message


def probe(platform: str, environ: Mapping[str, str] | None = None, timeout_s: float = PROBE_TIMEOUT_S) -> str | None:
    """Render one frame with ``MUJOCO_GL=platform`` in a child process (:func:`_probe_child`): None if it works,
    else why not (one line). Nothing the child or its libraries print reaches the terminal."""
    env = {**(os.environ if environ is None else environ), MUJOCO_GL: platform}
    env.pop(VERIFIED, None)
    here = str(Path(__file__).resolve().parents[1])  # this copy of ur3hanoi, whatever the child's path
    code = f"import sys; sys.path.insert(0, {here!r}); from ur3hanoi.opengl import _probe_child; _probe_child()"
    try:  # on any exception (a Ctrl-C), subprocess.run kills the child before raising
        proc = subprocess.run([sys.executable, "-c", code, str(os.getpid()), platform], env=env,
                              stdin=subprocess.DEVNULL, capture_output=True, text=True, errors="replace",
                              timeout=timeout_s, check=False)
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
    return printable(_said(said), 160)


_LIBRARIES = {"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}
"""The library each headless platform loads first (Debian's names): when it does not load, that is the reason."""


def _probe_child() -> None:
    """A probe's child (``python -c``; argv: the parent's pid, the platform): renders one 16x16 frame with the
    ``MUJOCO_GL`` it was given and prints ``ok``, or the reason on one line: GLFW's first error (a warning, kept
    from the terminal), else why the platform's library does not load, else the exception. Dies with its parent."""
    import warnings

    from ur3hanoi.lifecycle import child_start

    child_start(int(sys.argv[1]))
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            import mujoco

            renderer = mujoco.Renderer(mujoco.MjModel.from_xml_string("<mujoco/>"), 16, 16)
            renderer.render()
            renderer.close()
        except Exception as exc:
            print(_why(exc, said, sys.argv[2]), flush=True)
            sys.exit(1)
    print("ok", flush=True)


def _why(exc: Exception, said: list[warnings.WarningMessage], platform: str) -> str:
    """Why rendering with ``platform`` failed with ``exc``, the library's warnings ``said`` on the way (one line)."""
    glfw = [w for w in said if w.category.__name__ == "GLFWError"]
    if glfw:
        return _said(str(glfw[0].message))
    library = _LIBRARIES.get(platform.strip().lower())
    if library is not None:
        import ctypes

        try:
            ctypes.CDLL(library)
        except OSError as missing:
            return _said(str(missing))
    return _said(f"{type(exc).__name__}: {exc}")


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
            return Choice(known.get(name, Platform(name, f"MuJoCo's {name!r} platform", "")), chosen=False)
        raise SimulationError(f"offscreen rendering cannot use {MUJOCO_GL}={quote(given)} (set in the environment): "
                              f"{reason}; {_needs(name)}; or unset {MUJOCO_GL} to let ur3hanoi choose")
    tried: list[str] = []
    passed_over: list[str] = []
    for platform in PLATFORMS:
        no_display = display_available(env) if platform is GLFW else None
        if no_display is not None:
            tried.append(f"{platform.title}: {no_display}")
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
_TOO_LATE: list[bool] = []  # MuJoCo was imported with MUJOCO_GL unset before the answer was written


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
        if MUJOCO_GL not in env and "mujoco" in sys.modules:
            _TOO_LATE.append(True)  # this process keeps MuJoCo's default; the ones it starts get the answer
        env[MUJOCO_GL] = answer.platform.name
    env[VERIFIED] = f"{answer.platform.name} {'chosen' if answer.chosen else 'set'}"
    return answer


def render_failed(reason: str, environ: Mapping[str, str] | None = None) -> str:
    """The one line when creating an offscreen renderer failed in this process (``reason``: the library's)."""
    env = os.environ if environ is None else environ
    given = env.get(MUJOCO_GL)
    if given is None or _TOO_LATE:
        return (f"offscreen rendering is unavailable: {reason}; MuJoCo was imported with {MUJOCO_GL} unset (GLFW, "
                f"which needs a display): call ur3hanoi.opengl.use_platform() before importing MuJoCo, or set "
                f"{MUJOCO_GL}")
    return f"offscreen rendering with {MUJOCO_GL}={quote(given)} failed: {reason}; {_needs(given.strip().lower())}"


def offscreen_renderer(model: mujoco.MjModel, height: int, width: int) -> mujoco.Renderer:
    """``mujoco.Renderer(model, height, width)`` in this process, with the platform MuJoCo was imported with.

    Raises:
        SimulationError: the platform cannot make an OpenGL context (:func:`render_failed`); what its library says
            (GLFW's warnings) goes into that one line, not onto the terminal.
        ValueError: a size the model's offscreen framebuffer does not hold (a bug of the caller, not OpenGL).
    """
    import warnings

    import mujoco

    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        try:
            return mujoco.Renderer(model, height, width)
        except ValueError:
            raise
        except Exception as exc:
            reason = _why(exc, said, os.environ.get(MUJOCO_GL, GLFW.name))
    raise SimulationError(render_failed(reason))


__all__ = ["EGL", "GLFW", "MUJOCO_GL", "OSMESA", "PLATFORMS", "PROBE_TIMEOUT_S", "VERIFIED", "Choice", "Platform",
           "choose", "display_available", "offscreen_renderer", "probe", "render_failed", "use_platform"]
