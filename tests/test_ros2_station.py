"""``ros2-station`` / ``ros2-solve`` (ur3hanoi.ros2.station, .client, .dds): the bridge's behaviour without DDS, then
over real Cyclone DDS inside a private network namespace: ros2-solve solves 1 -> 3 on the UR3e station and halts
on a missing block; bridge timing moves take 2 s; malformed commands are dropped with a log line."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from tests.ros2_support import in_netns, requires_netns
from ur3hanoi.remote.movej import plan_movej
from ur3hanoi.ros2.dds import cyclone_config
from ur3hanoi.ros2.station import BRIDGE_MOVE_S, Ros2Station, Ros2StationOptions, bridge_speed
from ur3hanoi.station import load_station

REPO = Path(__file__).resolve().parents[1]


@pytest.mark.parametrize("delta", [0.05, 0.7, 2.5])
def test_bridge_speed_gives_the_bridges_fixed_2_s_move(delta: float) -> None:
    q0 = np.radians([120.0, -90.0, 90.0, -90.0, -90.0, 0.0])
    q1 = q0 + np.array([delta, -0.3 * delta, 0.1, 0.0, 0.2 * delta, 0.0])
    v, a = bridge_speed(q0, q1)
    lim = load_station("ur3e_sim").limits
    move = plan_movej(q0, q1, v, a, lim.v_max, lim.a_max)
    assert move.duration == pytest.approx(BRIDGE_MOVE_S, abs=1e-9)
    assert plan_movej(q0, q0, *bridge_speed(q0, q0), lim.v_max, lim.a_max).duration == 0.0  # suction-only


def test_station_drops_non_6_destinations_and_converts_the_course_convention() -> None:
    logged: list[str] = []
    st = Ros2Station(Ros2StationOptions(), out=lambda s: None, log=logged.append)
    home = np.array(st.station.q_home)
    assert st.position() == pytest.approx(home - np.array([math.pi / 2, 0, 0, -math.pi / 2, 0, 0]), abs=1e-6)
    assert not st.handle([0.0] * 5, 0.0, 0.0, True)  # v = a = 0 would be refused by ros-station; the bridge ignores
    assert logged == ["[ERROR] ur3e/command dropped, the arm does not move: destination has 5 values: expected 6 "
                      "joint angles [rad]"]
    course = home - np.array([math.pi / 2, 0, 0, -math.pi / 2, 0, 0]) + np.array([0.1, 0, 0, 0, 0, 0])
    assert st.handle(course.tolist(), 0.0, 0.0, False)
    queued = st.driver.queue[-1]
    assert queued.destination == pytest.approx(home + np.array([0.1, 0, 0, 0, 0, 0]), abs=1e-12)
    assert st.is_ready  # always, with the bridge's timing
    assert st.report()["suction"]["profile"] == "real" and st.report()["station"]["robot"] == "ur3e"


def test_default_dds_configuration_is_loopback_only() -> None:
    xml = cyclone_config()
    assert '<NetworkInterface name="lo"/>' in xml and "<AllowMulticast>false</AllowMulticast>" in xml
    assert '<Peer address="127.0.0.1"/>' in xml
    assert "NetworkInterface" not in cyclone_config("lab") and "AllowMulticast" not in cyclone_config("lab")
    with pytest.raises(ValueError, match="interface"):
        cyclone_config("eth0'/><x")


@pytest.mark.dds
@requires_netns
def test_ros2_solve_solves_on_the_ur3e_station_over_dds(tmp_path: Path) -> None:
    report = tmp_path / "report.json"
    script = f"""
$UR3HANOI ros2-station --timing honest --report {report} > {tmp_path}/st.out 2> {tmp_path}/st.err &
ST=$!
wait_ready {tmp_path}/st.out || exit 90
$UR3HANOI ros2-solve --start 1 --end 3 --v 4 --a 4 --json
CODE=$?
kill -INT $ST; wait $ST; echo "station exit $?" >&2
exit $CODE
"""
    result = in_netns(script, 240.0, REPO)
    assert result.returncode == 0, result.stdout + result.stderr + (tmp_path / "st.err").read_text()
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["status"] == "solved" and outcome["moves"] == 7
    assert "station exit 0" in result.stderr
    r = json.loads(report.read_text())
    assert {(b["block"], b["tower"], b["height"]) for b in r["final"]["blocks"]} == {(1, 3, 1), (2, 3, 2), (3, 3, 3)}
    assert r["final"]["at_home"] and not r["final"]["suction_on"]
    assert r["commands"]["rejected"] == 0 and r["transport"]["network"] == "loopback"
    assert r["suction"]["profile"] == "real"
    assert "ready on ROS_DOMAIN_ID 0 (loopback): ur3e_sim" in (tmp_path / "st.out").read_text()


@pytest.mark.dds
@requires_netns
def test_bridge_timing_and_halt_on_a_missing_block_over_dds(tmp_path: Path) -> None:
    """Bridge timing: every move lasts 2 s; the top block removed: ros2-solve halts (exit 3), suction off, home."""
    report = tmp_path / "report.json"
    script = f"""
$UR3HANOI ros2-station --remove-block 3 --report {report} > {tmp_path}/st.out 2> {tmp_path}/st.err &
ST=$!
wait_ready {tmp_path}/st.out || exit 90
$UR3HANOI ros2-solve --start 1 --end 3 --json
CODE=$?
kill -INT $ST; wait $ST; echo "station exit $?" >&2
exit $CODE
"""
    result = in_netns(script, 240.0, REPO)
    assert result.returncode == 3, result.stdout + result.stderr
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["status"] == "halted" and "tower 1 height 3" in outcome["error"]
    r = json.loads(report.read_text())
    assert r["transport"]["timing"] == "bridge"
    durations = [m["duration_s"] for m in r["executed"] if m["duration_s"] > 0]
    assert durations and all(abs(d - BRIDGE_MOVE_S) < 1e-9 for d in durations)
    assert r["final"]["at_home"] and not r["final"]["suction_on"]
    assert [e["kind"] for e in r["suction_events"]].count("grasp") == 0
