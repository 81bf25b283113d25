"""RateLimitedLog: a flood of messages writes at most one line per topic and second, and loses no count."""

from __future__ import annotations

import itertools
import re

from ur3hanoi.interface.common.lograte import RateLimitedLog


class Clock:
    def __init__(self) -> None:
        self.t = 100.0

    def __call__(self) -> float:
        return self.t


def test_a_flood_writes_one_line_per_second_with_counts():
    clock, lines = Clock(), []
    log = RateLimitedLog(lambda level, text: lines.append((clock.t, level, text)), clock=clock)
    sent = 0
    for _ in range(10_000):  # 10 s at 1 kHz
        log.log("ur3/command rejected", "error", "queue full" if sent % 3 else "too slow")
        sent += 1
        clock.t += 1e-3
        log.flush()
    log.flush(force=True)
    times = [t for t, _, _ in lines]
    assert all(b - a >= 1.0 - 1e-9 for a, b in itertools.pairwise(times))
    assert len(lines) <= 11
    counted = 1 + sum(int(m.group(1)) for _, _, text in lines[1:]
                      if (m := re.search(r": (\d+) more in the last", text)))
    assert counted == sent
    assert lines[1][2].startswith("ur3/command rejected: ") and "x queue full" in lines[1][2]


def test_a_quiet_topic_logs_at_once_and_summaries_name_the_reasons():
    clock, lines = Clock(), []
    log = RateLimitedLog(lambda level, text: lines.append((level, text)), clock=clock, max_reasons=2)
    log.log("a", "info", "first")
    for reason in ("r1", "r2", "r3", "r1"):
        clock.t += 0.05
        log.log("a", "warn", reason)
    log.log("b", "error", "other topic")
    assert lines == [("info", "a: first"), ("error", "b: other topic")]
    clock.t += 1.0
    log.flush()
    assert lines[2] == ("warn", "a: 4 more in the last 1.2 s: 2 x r1; 1 x r2; 1 x other reasons")
    clock.t += 5.0
    log.log("a", "info", "quiet again")
    assert lines[-1] == ("info", "a: quiet again") and log.lines == 4
