"""What a server's transport threads hand to its control loop: a bounded inbox, so that a flood cannot stall the
loop or grow memory (more than :data:`INBOX_MAX` messages waiting are refused, counted per kind)."""

from __future__ import annotations

import threading
from collections import deque
from typing import Any

INBOX_MAX = 200
"""Messages the callbacks may leave for the control loop; more are refused (counted, logged once a second)."""


class Inbox:
    """Messages ``(kind, payload)`` offered from any thread, taken by the control loop."""

    def __init__(self, size: int = INBOX_MAX) -> None:
        self.size = size
        self._items: deque[tuple[str, Any]] = deque()
        self._overflow: dict[str, int] = {}
        self._overflow_lock = threading.Lock()

    def offer(self, kind: str, payload: Any) -> None:
        """Called in the transport's threads: keep a message for the control loop, or count it when full."""
        if len(self._items) < self.size:
            self._items.append((kind, payload))
        else:
            with self._overflow_lock:
                self._overflow[kind] = self._overflow.get(kind, 0) + 1

    def take(self) -> tuple[dict[str, int], list[tuple[str, Any]]]:
        """(messages refused since the last take, per kind; the messages waiting now, in order): at most what the
        inbox held when called, so a flood cannot hold the loop."""
        with self._overflow_lock:
            overflow, self._overflow = self._overflow, {}
        return overflow, [self._items.popleft() for _ in range(len(self._items))]
