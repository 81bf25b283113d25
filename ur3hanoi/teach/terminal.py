"""The plain terminal teach runs in: keys without Enter, a few live status lines redrawn in place, messages above.

- :class:`Keys` puts standard input in cbreak mode (each key arrives at once, nothing is echoed; Ctrl-C still
  interrupts) and restores the terminal's settings on every way out. A terminal that goes away (end of input,
  SIGHUP) or SIGTERM ends the session with :class:`TerminalGoneError` at the next read of the keys: the signal handler
  only takes note, so no file write is ever cut short by it.
- :class:`Screen` writes messages as lines and keeps the live status as the last lines of the screen, redrawn with
  two ANSI sequences (cursor up, clear to the end of the screen) every VT100-like terminal knows; lines are cut to
  the terminal's width so the redraw never breaks. Without a terminal on standard output it prints messages only.
"""

from __future__ import annotations

import contextlib
import os
import select
import shutil
import signal
import sys
import termios
import tty
from collections.abc import Sequence
from types import FrameType, TracebackType
from typing import Any, TextIO

ESC = "\x1b"


class TerminalGoneError(Exception):
    """The terminal closed (end of input, SIGHUP) or SIGTERM came: ``hangup`` is True when nothing can be shown
    any more."""

    def __init__(self, why: str, hangup: bool = True) -> None:
        super().__init__(why)
        self.hangup = hangup


_STOP_SIGNALS = (signal.SIGHUP, signal.SIGTERM)


class Keys:
    """Standard input in cbreak mode (a context manager); :meth:`read` returns the keys typed so far."""

    def __init__(self, stream: TextIO | None = None) -> None:
        self.fd = (stream or sys.stdin).fileno()
        self._saved: list[Any] | None = None
        self._old_handlers: dict[int, object] = {}
        self._signal: int | None = None

    def _note(self, signum: int, frame: FrameType | None) -> None:
        self._signal = signum

    def __enter__(self) -> Keys:
        self._saved = termios.tcgetattr(self.fd)
        for sig in _STOP_SIGNALS:
            self._old_handlers[sig] = signal.signal(sig, self._note)
        tty.setcbreak(self.fd, termios.TCSANOW)
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if self._saved is not None:
            with contextlib.suppress(termios.error):  # the terminal is gone: nothing to restore
                termios.tcsetattr(self.fd, termios.TCSADRAIN, self._saved)
        for sig, old in self._old_handlers.items():
            signal.signal(sig, old)  # type: ignore[arg-type]

    def read(self, timeout_s: float) -> str:
        """The keys typed within ``timeout_s`` [s] ("" if none); an escape sequence (an arrow key) is dropped.

        Raises:
            TerminalGoneError: end of input, SIGHUP (the terminal closed) or SIGTERM.
        """
        if self._signal is not None:
            name = signal.Signals(self._signal).name
            raise TerminalGoneError(f"stopped by {name}", hangup=self._signal == signal.SIGHUP)
        ready, _, _ = select.select([self.fd], [], [], timeout_s)
        if not ready:
            return ""
        try:
            data = os.read(self.fd, 64)
        except OSError as exc:  # EIO once the terminal has hung up
            raise TerminalGoneError(f"cannot read the terminal: {exc.strerror}") from None
        if not data:
            raise TerminalGoneError("end of input")
        text = data.decode("utf-8", "replace")
        return text.split(ESC, 1)[0]


class Screen:
    """Messages and a live status block on ``out`` (see the module docstring)."""

    def __init__(self, out: TextIO | None = None) -> None:
        self.out = out or sys.stdout
        self.live = self.out.isatty()
        self._drawn = 0

    def _width(self) -> int:
        return max(20, shutil.get_terminal_size((100, 24)).columns - 1)

    def _clear(self) -> None:
        if self._drawn:
            up = f"{ESC}[{self._drawn - 1}A" if self._drawn > 1 else ""
            self.out.write(f"\r{up}{ESC}[J")
            self._drawn = 0

    def say(self, lines: Sequence[str]) -> None:
        """Write ``lines`` as messages (above the status, which the next :meth:`draw` puts back)."""
        if not lines:
            return
        self._clear()
        self.out.write("".join(f"{line}\n" for line in lines))
        self.out.flush()

    def draw(self, status: Sequence[str]) -> None:
        """Replace the status block with ``status`` (on a terminal only)."""
        if not self.live:
            return
        self._clear()
        width = self._width()
        self.out.write("\n".join(line[:width] for line in status))
        self.out.flush()
        self._drawn = len(status)

    def close(self) -> None:
        """Take the status block off the screen (nothing when the terminal is gone)."""
        try:
            self._clear()
            self.out.flush()
        except OSError:
            self._drawn = 0


__all__ = ["Keys", "Screen", "TerminalGoneError"]
