"""``python -m ur3hanoi``: the same as the ``ur3hanoi`` command (works without the command on PATH)."""

import sys

from ur3hanoi.cli.main import main

sys.exit(main())
