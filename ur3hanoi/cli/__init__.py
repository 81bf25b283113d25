"""The ``ur3hanoi`` command line: ``tables``, ``check-table``, ``calibrate``, ``plan``, ``solve``.

One module per command (``add`` builds its parser, ``run`` executes it); :mod:`~ur3hanoi.cli.options` holds every
numeric option's range, :mod:`~ur3hanoi.cli.exit_codes` the exit codes and which error maps to which, and
:mod:`~ur3hanoi.cli.main` the entry point that turns every error into one line on stderr. The ROS 1 and ROS 2
commands (:mod:`~ur3hanoi.cli.ros`, :mod:`~ur3hanoi.cli.ros2`) share their options, solve and outcome handling
through :mod:`~ur3hanoi.cli.remote`.
"""

import os

# NumPy's OpenBLAS starts a busy-waiting thread per core when it is imported: on a shared 2-core machine that is up
# to 0.1 s of CPU at every start, for 6x6 matrices that never use the threads. The command keeps BLAS on one thread
# unless the user chose otherwise (set before anything imports NumPy).
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from typing import TYPE_CHECKING, Any

from ur3hanoi.cli.main import build_parser, help_markdown, main

if TYPE_CHECKING:
    from ur3hanoi.cli.prompt import prompt_tower


def __getattr__(name: str) -> Any:
    if name == "prompt_tower":  # imported on use: a run imports only its own command's module
        from ur3hanoi.cli.prompt import prompt_tower

        return prompt_tower
    raise AttributeError(f"module 'ur3hanoi.cli' has no attribute {name!r}")


__all__ = ["build_parser", "help_markdown", "main", "prompt_tower"]
