"""ur3hanoi.interface.urdriver.joint_record: every joint state while recording, in bounded memory (thinned evenly,
never cut off)."""

from __future__ import annotations

import numpy as np
import pytest

from ur3hanoi.interface.urdriver.joint_record import CAPACITY, JointRecord


def feed(record: JointRecord, n: int, start: int = 0) -> None:
    for i in range(start, start + n):
        record.label = i // 10
        record.add(float(i), np.full(6, float(i)))


def test_records_only_while_recording_and_start_forgets() -> None:
    r = JointRecord(capacity=8)
    feed(r, 3)
    assert len(r.samples()[0]) == 0 and r.received == 0
    r.start()
    feed(r, 5)
    r.stop()
    feed(r, 5, start=100)
    t, q, label = r.samples()
    np.testing.assert_array_equal(t, np.arange(5.0))
    np.testing.assert_array_equal(label, np.zeros(5))
    np.testing.assert_array_equal(q, np.repeat(np.arange(5.0)[:, None], 6, axis=1))
    assert r.received == 5 and r.stride == 1
    r.label = 4
    r.start()
    assert len(r.samples()[0]) == 0 and r.label == 0


@pytest.mark.parametrize("n", [8, 9, 17, 100, 1000])
def test_a_full_record_thins_evenly_and_keeps_the_whole_span(n: int) -> None:
    r = JointRecord(capacity=8)
    r.start()
    feed(r, n)
    t, q, label = r.samples()
    assert len(t) <= 8 and r.received == n
    np.testing.assert_array_equal(t, np.arange(0, n, r.stride, dtype=float))  # every stride-th message, from the first
    np.testing.assert_array_equal(q[:, 3], t)
    np.testing.assert_array_equal(label, t // 10)  # each with the label it arrived under
    assert t[-1] > n - 1 - r.stride


def test_the_default_holds_a_solve_at_the_e_series_rate_unthinned() -> None:
    assert CAPACITY / 500.0 > 2 * 60.0  # seconds at 500 Hz: a 3-block solve (27 s) even at a slider of 25 %
    r = JointRecord()
    r.start()
    feed(r, 14_000)
    assert r.stride == 1 and len(r.samples()[0]) == 14_000


def test_an_odd_capacity_is_refused() -> None:
    with pytest.raises(ValueError, match="capacity 7 is invalid"):
        JointRecord(capacity=7)
