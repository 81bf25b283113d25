"""The ``ur3hanoi`` parser and entry point: one line on stderr for every error, never a traceback.

A library error (:class:`~ur3hanoi.errors.Ur3HanoiError`) prints ``ur3hanoi: error: <message>`` and exits with the
code of :data:`ur3hanoi.cli.exit_codes.EXIT_CODES`; a bad option prints ``ur3hanoi: error: argument ... (see
ur3hanoi <command> --help)`` and exits 2; anything unexpected prints ``ur3hanoi: error: internal error in ur3hanoi
<command>: ...`` and exits 70, and ``--debug`` shows its traceback instead. SIGTERM is handled like a Ctrl-C (the
same clean-up: child processes stopped, an old output kept; :func:`ur3hanoi.lifecycle.sigterm_raises`) and exits
143. A library warning (:class:`~ur3hanoi.errors.Ur3HanoiWarning`) prints ``ur3hanoi: warning: <message>``.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys
import warnings
from collections.abc import Sequence
from typing import NoReturn

from ur3hanoi.cli import exit_codes
from ur3hanoi.errors import Ur3HanoiError, Ur3HanoiWarning, printable
from ur3hanoi.lifecycle import Terminated, sigterm_raises
from ur3hanoi.version import __version__

COMMAND_MODULES: dict[str, str] = {
    "tables": "tables", "check-table": "check_table", "calibrate": "calibrate", "teach": "teach",
    "check-arm": "check_arm", "plan": "plan",
    "solve": "solve", "ros-station": "ros", "ros-solve": "ros", "ros-env": "ros", "ros2-station": "ros2",
    "ros2-solve": "ros2", "ros2-env": "ros2"}
"""Each command's module in :mod:`ur3hanoi.cli`, in the order ``--help`` lists them. A run imports only its own
command's module (the others' options cost start-up time and nothing else)."""
ERROR_PREFIX = "ur3hanoi: error:"
"""What every error line on stderr starts with: bad input, bad options, a suction fault, an internal error."""
_DEBUG_HELP = "on an internal error, show the Python traceback (for a bug report)"


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors under the one prefix: ``ur3hanoi: error: argument --rate: ... (see ur3hanoi plan
    --help)``."""

    def error(self, message: str) -> NoReturn:
        self.exit(exit_codes.BAD_INPUT, f"{ERROR_PREFIX} {_one_line(message)} (see {self.prog} --help)\n")


def _one_line(text: object) -> str:
    return printable(" ".join(str(text).split()), 2000)


def build_parser(command: str | None = None) -> argparse.ArgumentParser:
    """The ``ur3hanoi`` parser with every command, or only with ``command``'s module (see :data:`COMMAND_MODULES`;
    an unknown name gives every command, so the error lists them all)."""
    parser = _Parser(prog="ur3hanoi", description="UR3 Tower of Hanoi lab toolkit.")
    parser.add_argument("--version", action="version", version=f"ur3hanoi {__version__}")
    parser.add_argument("--debug", action="store_true", help=_DEBUG_HELP)
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    modules = dict.fromkeys(COMMAND_MODULES.values())
    for module in [COMMAND_MODULES[command]] if command in COMMAND_MODULES else modules:
        importlib.import_module(f"ur3hanoi.cli.{module}").add(sub)
    for p in sub.choices.values():
        # Also accepted after the command; SUPPRESS keeps a --debug given before it.
        p.add_argument("--debug", action="store_true", default=argparse.SUPPRESS, help=_DEBUG_HELP)
    return parser


def help_markdown(width: int = 100) -> str:
    """The command-line reference (``docs/cli.md``): ``--help`` of the command and of every subcommand, at a fixed
    width, one section per subcommand."""
    old = os.environ.get("COLUMNS")
    os.environ["COLUMNS"] = str(width)  # argparse wraps to the terminal width: pin it for a stable text
    try:
        parser = build_parser()
        parts = ["```text", "$ ur3hanoi --help", parser.format_help().rstrip(), "```"]
        sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
        for name, p in sub.choices.items():
            parts += ["", f"## `ur3hanoi {name}`", "", "```text", p.format_help().rstrip(), "```"]
    finally:
        if old is None:
            del os.environ["COLUMNS"]
        else:
            os.environ["COLUMNS"] = old
    return "\n".join(parts) + "\n"


def _show_warning(message: Warning | str, category: type[Warning], filename: str, lineno: int,
                  file: object = None, line: str | None = None) -> None:
    """``ur3hanoi: warning: <message>`` for a library warning, Python's own format for any other."""
    if issubclass(category, Ur3HanoiWarning):
        print(f"ur3hanoi: warning: {_one_line(message)}", file=sys.stderr)
    else:
        sys.stderr.write(warnings.formatwarning(message, category, filename, lineno, line))


def _exit_status(code: object) -> int:
    if code is None:
        return exit_codes.OK
    return code if isinstance(code, int) else exit_codes.BAD_INPUT


def _command_of(argv: Sequence[str]) -> str | None:
    """The command word of ``argv``: its first word that is not an option (the top-level options take no value)."""
    return next((a for a in argv if not a.startswith("-")), None)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``ur3hanoi`` with ``argv`` (default ``sys.argv[1:]``); returns the exit code, never raises
    (except with ``--debug`` on an internal error)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser(_command_of(argv))
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a usage error already printed
        return _exit_status(exc.code)
    prog = f"ur3hanoi {args.command}"
    try:
        with sigterm_raises(), warnings.catch_warnings():
            warnings.showwarning = _show_warning
            return int(args.func(args))
    except Ur3HanoiError as exc:
        print(f"{ERROR_PREFIX} {_one_line(exc)}", file=sys.stderr)
        return exit_codes.exit_code_for(exc)
    except Terminated:
        print(f"{prog}: terminated (SIGTERM)", file=sys.stderr)
        return exit_codes.TERMINATED
    except KeyboardInterrupt:
        print(f"{prog}: interrupted", file=sys.stderr)
        return exit_codes.INTERRUPTED
    except BrokenPipeError:
        # The reader of stdout went away (`| head`): nothing more to say; keep Python quiet at exit too.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
        return exit_codes.BROKEN_PIPE
    except Exception as exc:
        if args.debug:
            raise
        print(f"{ERROR_PREFIX} internal error in {prog}: {type(exc).__name__}: {_one_line(exc) or '(no message)'} "
              "(a bug: rerun with --debug for the traceback)", file=sys.stderr)
        return exit_codes.INTERNAL
