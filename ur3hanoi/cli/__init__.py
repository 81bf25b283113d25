"""The ``ur3hanoi`` command line: ``tables``, ``check-table``, ``calibrate``, ``plan``, ``solve``.

One module per command (``add`` builds its parser, ``run`` executes it); :mod:`~ur3hanoi.cli.options` holds every
numeric option's range, :mod:`~ur3hanoi.cli.exit_codes` the exit codes and which error maps to which, and
:mod:`~ur3hanoi.cli.main` the entry point that turns every error into one line on stderr.
"""

from ur3hanoi.cli.main import build_parser, help_markdown, main
from ur3hanoi.cli.solve import prompt_tower

__all__ = ["build_parser", "help_markdown", "main", "prompt_tower"]
