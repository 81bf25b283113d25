"""How every process ur3hanoi starts is tied to the one that started it: signals it obeys, and death with its parent.

A child inherits its parent's *ignored* signals and its signal mask across ``exec`` (handled signals are reset):
a child started by a process that ignores SIGINT ignores it too, and then stopping it takes a SIGKILL (the roscore
guard's rosmaster did, which made every station stop take 15 s). So each child starts with :func:`default_signals`
for the signals it is expected to obey (a ``preexec_fn`` of :mod:`subprocess` does it before ``exec``,
:func:`child_start` first thing in a ``multiprocessing`` child), and with :func:`die_with_parent`: Linux sends it a
signal (``PR_SET_PDEATHSIG``) when its parent dies, even by SIGKILL, where no clean-up code of the parent runs.

Processes ur3hanoi starts (each stopped on its parent's every exit path: normal end, error, SIGINT, SIGTERM, SIGKILL):

- the roscore guard (:mod:`ur3hanoi.interface.ros1.guard`, own session): the end of file on its stdin pipe (the station
  closed it or died), SIGINT or SIGTERM stop it; it stops rosmaster/roscore, which starts with SIGINT and SIGTERM at
  their defaults and dies with the guard;
- the station's rendering process (:mod:`ur3hanoi.interface.common.render`, ``spawn``): its pipe, SIGTERM, its parent's
  death; it ignores SIGINT on purpose (a Ctrl-C must not cut the video short: the station finishes it);
- the OpenGL probes (:func:`ur3hanoi.opengl.probe`: a ``python -c`` that renders one frame, before a command
  renders): waited for, killed by :func:`subprocess.run` on its timeout or on any exception (a Ctrl-C, SIGTERM
  raised by :func:`sigterm_raises`), and dies with its parent (:func:`child_start`, its first act: no
  ``preexec_fn``, so a threaded caller such as a Jupyter kernel may probe too);
- ``solve --video``'s rendering workers (:class:`ur3hanoi.sim.render.OffscreenRecorder`, a ``spawn`` pool):
  ``Pool.terminate`` (SIGTERM), their parent's death; ffmpeg (imageio-ffmpeg's) ends at the end of file of its
  stdin pipe; multiprocessing's resource tracker at the end of file of its own.

The commands that start processes take SIGTERM like SIGINT (:func:`sigterm_raises`): the same clean-up runs.
"""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Callable, Iterable, Iterator
from types import FrameType

PR_SET_PDEATHSIG = 1
PR_SET_CHILD_SUBREAPER = 36
STOP_SIGNALS: tuple[signal.Signals, ...] = (signal.SIGINT, signal.SIGTERM)
"""The signals that ask a process to stop."""


def prctl(option: int, value: int) -> None:
    """Linux ``prctl(option, value)`` (a no-op where libc has none)."""
    with contextlib.suppress(AttributeError, OSError):
        import ctypes  # here: every command imports this module, only the ones that start processes need it

        ctypes.CDLL(None, use_errno=True).prctl(option, value, 0, 0, 0)


def default_signals(signals: Iterable[signal.Signals] = STOP_SIGNALS) -> None:
    """Give ``signals`` their default action and unblock them in this process (a child's first act)."""
    signals = tuple(signals)
    for s in signals:
        signal.signal(s, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, signals)


def die_with_parent(parent: int, sig: signal.Signals = signal.SIGTERM) -> None:
    """Have Linux send ``sig`` to this process when its parent (process id ``parent``) dies; if it already has
    (this process was re-parented before it got here), send it now."""
    prctl(PR_SET_PDEATHSIG, int(sig))
    if os.getppid() != parent:
        os.kill(os.getpid(), sig)


def child_preexec(signals: Iterable[signal.Signals] = STOP_SIGNALS,
                  death: signal.Signals = signal.SIGTERM) -> Callable[[], None]:
    """A ``preexec_fn`` for :class:`subprocess.Popen`: the child starts with ``signals`` at their defaults and gets
    ``death`` when this process dies. Use it from a single-threaded process (``preexec_fn``'s own rule), and from
    the thread that lives as long as the child should (the kernel ties ``PR_SET_PDEATHSIG`` to that thread)."""
    parent = os.getpid()
    signals = tuple(signals)

    def preexec() -> None:
        default_signals(signals)
        die_with_parent(parent, death)

    return preexec


def child_start(parent: int, signals: Iterable[signal.Signals] = (signal.SIGTERM,),
                death: signal.Signals = signal.SIGTERM) -> None:
    """First thing in a ``multiprocessing`` child: ``signals`` at their defaults, ``death`` when ``parent`` dies."""
    default_signals(signals)
    die_with_parent(parent, death)


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised like a Ctrl-C so that the same clean-up runs (:func:`sigterm_raises`)."""


def _terminated(_signum: int, _frame: FrameType | None) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_IGN)  # once: a second SIGTERM must not cut the clean-up short
    raise Terminated


@contextlib.contextmanager
def sigterm_raises() -> Iterator[None]:
    """Inside: SIGTERM raises :class:`Terminated` (a :class:`KeyboardInterrupt`) in the main thread, once; the
    previous handler is restored after. Elsewhere than in the main thread: nothing (Python signals need it)."""
    try:
        previous = signal.signal(signal.SIGTERM, _terminated)
    except ValueError:  # not the main thread, where Python runs signal handlers: nothing to do
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)


__all__ = ["PR_SET_CHILD_SUBREAPER", "PR_SET_PDEATHSIG", "STOP_SIGNALS", "Terminated", "child_preexec", "child_start",
           "default_signals", "die_with_parent", "prctl", "sigterm_raises"]
