"""``python -m ur3hanoi.cli``: the same as the ``ur3hanoi`` command."""

import sys

from ur3hanoi.cli.main import main

sys.exit(main())
