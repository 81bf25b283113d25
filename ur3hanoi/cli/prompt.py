"""The start and end towers of a solve: from ``--start``/``--end``, or asked for on a terminal like the lab program
(``Enter the start tower <1 2 or 3>``, asked again until the answer is one of them)."""

from __future__ import annotations

import argparse
import sys

from ur3hanoi.cli.options import UsageError, check_number


def prompt_tower(what: str, n_towers: int, exclude: int | None = None) -> int:
    """Prompt like the lab program until a valid tower (1-based) is entered; returns it 0-based."""
    choices = " ".join(str(t) for t in range(1, n_towers + 1) if t - 1 != exclude)
    options = choices.rsplit(" ", 1)
    label = f"{options[0]} or {options[1]}" if len(options) == 2 else choices
    while True:
        try:
            text = input(f"Enter the {what} tower <{label}> ")
        except EOFError:
            raise UsageError(f"no {what} tower entered (end of input)") from None
        text = text.strip()
        if text.isdigit() and len(text) < 4 and 1 <= int(text) <= n_towers and int(text) - 1 != exclude:
            return int(text) - 1
        print(f"Please just enter the character {label}\n")


def towers(args: argparse.Namespace, n_towers: int, why: str, command: str) -> tuple[int, int]:
    """Start and end tower of ``command``, 0-based: from ``args.start``/``args.end`` (1-based, checked against
    ``n_towers``, ``why`` saying where that number comes from), the missing ones asked for on a terminal."""
    check_number("--start", args.start, n_towers, "a tower", why)
    check_number("--end", args.end, n_towers, "a tower", why)
    if args.start is not None and args.end is not None:
        return args.start - 1, args.end - 1
    if not sys.stdin.isatty():
        raise UsageError("--start and --end are required when stdin is not a terminal "
                         f"(towers 1..{n_towers}), e.g. ur3hanoi {command} --start 1 --end 3")
    start = args.start - 1 if args.start is not None else prompt_tower("start", n_towers)
    end = args.end - 1 if args.end is not None else prompt_tower("end", n_towers, exclude=start)
    return start, end
