"""A machine without OpenGL, made for a test: every EGL and OSMesa library file reads as empty (``/dev/null`` bound
over it in a private mount namespace: ``unshare -m``, or ``unshare -rm`` without root) and there is no display.

:func:`without_opengl` gives the command prefix and the environment; a test first checks that the hiding hides
(each platform's probe fails in it), so it cannot pass on a machine where it hid nothing.
"""

from __future__ import annotations

import os
import shlex
import subprocess
from pathlib import Path

from ur3hanoi.opengl import MUJOCO_GL, VERIFIED

HIDDEN_LIBRARIES = ("libEGL", "libOSMesa")
"""File name prefixes of the libraries hidden: EGL (glvnd's dispatcher and every vendor's, e.g. ``libEGL_mesa``) and
OSMesa."""


def library_files() -> list[str]:
    """The real files of :data:`HIDDEN_LIBRARIES` in the dynamic linker's folders (``ldconfig -p``,
    ``LD_LIBRARY_PATH``, the usual ones)."""
    folders = {"/lib", "/usr/lib", "/lib64", "/usr/lib64", "/usr/local/lib"}
    folders.update(p for p in os.environ.get("LD_LIBRARY_PATH", "").split(":") if p)
    cache = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True, check=False).stdout
    folders.update(str(Path(line.rsplit("=>", 1)[1].strip()).parent) for line in cache.splitlines() if "=>" in line)
    files = set()
    for folder in folders:
        for path in Path(folder).glob("*.so*") if Path(folder).is_dir() else ():
            if path.name.startswith(HIDDEN_LIBRARIES) and path.exists():
                files.add(str(path.resolve()))
    return sorted(files)


def without_opengl() -> tuple[list[str], dict[str, str]] | str:
    """(command prefix, environment) of a machine without OpenGL, or why it cannot be made here."""
    files = library_files()
    script = "set -e; " + "".join(f"mount --bind /dev/null {shlex.quote(f)}; " for f in files) + 'exec "$@"'
    env = {k: v for k, v in os.environ.items()
           if k not in (MUJOCO_GL, VERIFIED, "DISPLAY", "WAYLAND_DISPLAY", "PYOPENGL_PLATFORM")}
    reasons = []
    for unshare in (["unshare", "-m"], ["unshare", "-rm"]):
        prefix = [*unshare, "sh", "-c", script, "sh"]
        try:
            done = subprocess.run([*prefix, "true"], capture_output=True, text=True, timeout=30, check=False)
        except OSError as exc:
            return f"cannot run unshare: {exc}"
        if done.returncode == 0:
            return prefix, env
        reasons.append(f"{' '.join(unshare)}: {done.stderr.strip()[:120]}")
    return "cannot hide the OpenGL libraries in a private mount namespace (" + "; ".join(reasons) + ")"
