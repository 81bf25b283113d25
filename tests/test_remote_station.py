"""The transport-neutral station (ur3hanoi.remote.station) through both bindings, in process (no ROS, no DDS):
a command flood is counted in full while the report, the records and the log lines stay bounded."""

from __future__ import annotations

import json
from collections.abc import Callable
from types import SimpleNamespace

import pytest

from ur3hanoi.remote.station import LAG_BINS_MS, LoopTiming, StationCore
from ur3hanoi.ros.station import RosStation, StationOptions
from ur3hanoi.ros2.station import Ros2Station, Ros2StationOptions

Station = tuple[StationCore, list[float]]


def _ros1(log: list[str]) -> Station:
    """``ros-station`` and where its arm is (controller convention)."""
    node = RosStation(StationOptions(), out=log.append)
    return node, [float(x) for x in node.world.q]


def _ros2(log: list[str]) -> Station:
    """``ros2-station`` (timing honest, so commands execute as sent) and where its arm is (course convention)."""
    node = Ros2Station(Ros2StationOptions(timing="honest"), out=lambda _s: None, log=log.append)
    return node, node.position()


@pytest.mark.parametrize("make", [_ros1, _ros2], ids=["ros", "ros2"])
def test_the_report_does_not_grow_with_the_number_of_commands(make: Callable[[list[str]], Station]) -> None:
    """1 kHz against 125 Hz (8 commands per period: the lab's re-publish of where the arm is, suction toggled) for
    1600 and 8000 commands: every command counted, the same report size after 5x the commands (it was about 5 kB
    per command), a few log lines however many are refused."""
    sizes, counts = [], []
    for n in (1600, 8000):
        logged: list[str] = []
        node, here = make(logged)
        for i in range(n):
            node.on_command(SimpleNamespace(destination=here, v=4.0, a=4.0, io_0=bool(i % 2)))
            if i % 8 == 7:
                node.cycle()
        report = node.report()
        sizes.append(len(json.dumps(report, indent=1)))
        counts.append(report["commands"])
        assert len(logged) <= 3, logged[:5]  # a few cycles of wall time: the first line and at most a summary
    assert [c["executed"] + c["rejected"] + c["queued"] for c in counts] == [1600, 8000]
    assert counts[0]["executed"] > 150 and counts[1]["executed"] > 900 and counts[1]["rejected"] > 6000
    assert report["event_counts"]["suction_on"] + report["event_counts"]["suction_off"] > 100
    assert len(report["executed"]) <= 100 and len(report["rejected"]) <= 100
    assert sizes[1] <= 1.02 * sizes[0], sizes


def test_loop_timing_counts_lag_into_its_histogram() -> None:
    t = LoopTiming(0.008)
    for lag_ms in (0.5, 1.5, 9.0, 100.0, -0.2):
        t.add(lag_ms / 1e3)
    d = t.as_dict(wall_s=0.04)
    assert d["cycles"] == 5 and d["late_cycles"] == 2 and d["publish_rate_hz"] == pytest.approx(125.0, abs=1e-9)
    assert d["worst_lag_s"] == pytest.approx(0.1, abs=1e-9)
    assert d["mean_lag_s"] == pytest.approx((0.5 + 1.5 + 9.0 + 100.0) / 5e3, abs=1e-6)
    hist = d["lag_histogram_ms"]
    assert list(hist) == [f"<{b:g}" for b in LAG_BINS_MS] + [f">={LAG_BINS_MS[-1]:g}"]
    assert hist["<1"] == 2 and hist["<2"] == 1 and hist["<16"] == 1 and hist[">=32"] == 1
