"""Processes that race on the user's cache: each holds its built entry back, so all of them miss and build.

A racer is ``python -c PRELUDE + body``. The prelude wraps :func:`ur3hanoi.io.cache.load` (recording ``"hit"`` or
``"miss"`` with the entry's kind in ``cache_events``) and :func:`ur3hanoi.io.cache.store` (sleeping ``hold_s`` first),
loads ``lab_sim`` as ``station`` and waits until every racer has started, so the races are real.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

PRELUDE = textwrap.dedent("""
    import hashlib, os, sys, time
    from pathlib import Path
    import ur3hanoi.io.cache as cache
    from ur3hanoi.station.calibration import load_station
    real_load, real_store, cache_events = cache.load, cache.store, []
    def load(kind, key):
        payload = real_load(kind, key)
        cache_events.append(("hit" if payload is not None else "miss", kind))
        return payload
    def store(kind, key, payload):
        time.sleep(float(sys.argv[2]))  # hold the built entry back: the other process misses too
        return real_store(kind, key, payload)
    cache.load, cache.store = load, store
    station = load_station("lab_sim")
    ready, n_racers = Path(sys.argv[1]), int(sys.argv[3])
    (ready / str(os.getpid())).touch()
    deadline = time.monotonic() + 60
    while len(list(ready.iterdir())) < n_racers and time.monotonic() < deadline:  # all racers start together
        time.sleep(0.001)
""")


def start_racer(body: str, ready: Path, hold_s: float, n_racers: int) -> subprocess.Popen[str]:
    """Start one racer running ``body`` after :data:`PRELUDE`; ``ready`` is the folder of the start barrier."""
    ready.mkdir(exist_ok=True)
    return subprocess.Popen([sys.executable, "-c", PRELUDE + textwrap.dedent(body), str(ready), str(hold_s),
                             str(n_racers)], cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
