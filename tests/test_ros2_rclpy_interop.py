"""ros2-station against a real rclpy (ROS 2 Jazzy and Kilted wheels from PyPI, Fast-RTPS 2.14 / Fast DDS 3.2, each in
its own throwaway environment built by tests/rclpy_support.py), everything inside a private network namespace:
the graph shows the node, its topics, types, hashes and QoS; an ENME480-style rclpy program solves 1 -> 3 and
halts on a removed block."""

from __future__ import annotations

import json
import math
import shlex
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from tests.rclpy_support import DISTROS, build_env, python_for
from tests.ros2_support import NETNS_PROBLEM, REPO, in_netns
from ur3hanoi.convention import from_controller
from ur3hanoi.ros2.msgs import TYPE_HASHES
from ur3hanoi.station import load_station

TESTS = Path(__file__).resolve().parent
PYTHONS = {distro: python_for(version) for distro, (version, _) in DISTROS.items()}

pytestmark = [pytest.mark.rclpy, pytest.mark.skipif(NETNS_PROBLEM is not None, reason=NETNS_PROBLEM or "")]


@pytest.fixture(scope="module", params=sorted(DISTROS))
def rclpy_env(request: pytest.FixtureRequest) -> dict[str, str]:
    distro = request.param
    python = PYTHONS[distro]
    if python is None:
        pytest.skip(f"no Python {DISTROS[distro][0]} interpreter for the ROS 2 {distro} rclpy wheels")
    return {**build_env(distro, python), "DISTRO": distro}


def _peer(env: dict[str, str], *args: str) -> str:
    """The shell command running a script with the rclpy environment (and only that process)."""
    assigns = [f"{k}={shlex.quote(v)}" for k, v in env.items() if k not in ("RCLPY_PYTHON", "DISTRO")]
    return " ".join(["env", *assigns, shlex.quote(env["RCLPY_PYTHON"]), *map(shlex.quote, args)])


def _station_script(tmp_path: Path, station_args: str, peer: str) -> str:
    return f"""
$UR3HANOI ros2-station {station_args} --report {tmp_path}/report.json > {tmp_path}/st.out 2> {tmp_path}/st.err &
ST=$!
wait_ready {tmp_path}/st.out || exit 90
{peer}
CODE=$?
kill -INT $ST; wait $ST; echo "station exit $?" >&2
exit $CODE
"""


def _graph(rclpy_env: dict[str, str], tmp_path: Path) -> dict[str, Any]:
    peer = _peer(rclpy_env, str(TESTS / "rclpy_graph_probe.py"))
    result = in_netns(_station_script(tmp_path, "", peer), 180.0, REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    graph: dict[str, Any] = json.loads(result.stdout.strip().splitlines()[-1])
    return graph


def test_graph_names_the_node(rclpy_env: dict[str, str], tmp_path: Path, request: pytest.FixtureRequest) -> None:
    """Jazzy reads ros_discovery_info and names the station's endpoints after ur3hanoi_station. Kilted (Fast DDS 3)
    does not match Cyclone's ros_discovery_info writer (still with rmw_dds_common's string<256> names), so it shows
    the endpoints as _CREATED_BY_BARE_DDS_APP_: a known gap, kept visible as a strict xfail."""
    if rclpy_env["DISTRO"] == "kilted":
        request.applymarker(pytest.mark.xfail(strict=True, reason="Kilted does not take Cyclone's ros_discovery_info"))
    graph = _graph(rclpy_env, tmp_path)
    assert "ur3hanoi_station" in graph["nodes"]
    assert {e["node"] for v in graph["publishers"].values() for e in v} == {"ur3hanoi_station"}


def test_graph_shows_topics_types_hashes_and_qos(rclpy_env: dict[str, str], tmp_path: Path) -> None:
    graph = _graph(rclpy_env, tmp_path)
    assert graph["topics"]["/ur3e/command"] == ["ur3e_mrc_msgs/msg/CommandUR3e"]
    assert graph["topics"]["/ur3e/position"] == ["ur3e_mrc_msgs/msg/PositionUR3e"]
    assert graph["topics"]["/ur3e/gripper_input"] == ["ur3e_mrc_msgs/msg/GripperInput"]
    assert graph["topics"]["/gripper/grasping"] == ["std_msgs/msg/Bool"]
    endpoints = [*graph["subscriptions"]["ur3e/command"], *(e for v in graph["publishers"].values() for e in v)]
    assert len(endpoints) == 4
    for e in endpoints:
        assert e["hash"] == TYPE_HASHES[e["type"]]
        assert (e["reliability"], e["durability"]) == ("RELIABLE", "VOLATILE")
    home_course = from_controller(np.array(load_station("ur3e_sim").q_home), "course")
    assert np.abs(np.array(graph["samples"]["position"]) - home_course).max() < 1e-3
    dig_in, a_in0, a_in1 = graph["samples"]["gripper"]
    assert dig_in == 0 and abs(a_in0 - 1.05) < 0.1 and a_in1 == 0.0  # suction off, `real` profile


def _student(tmp_path: Path, env: dict[str, str]) -> str:
    table = tmp_path / "lab2_data.yaml"
    from ur3hanoi import cli

    assert cli.main(["tables", "ur3e_sim", "--key", "sim_pos", "-o", str(table), "--convention", "course"]) == 0
    home = from_controller(np.array(load_station("ur3e_sim").q_home), "course")
    return _peer(env, str(TESTS / "enme480_student.py"), str(table), "1", "3", ",".join(repr(float(x)) for x in home))


def test_enme480_style_rclpy_program_solves_1_to_3(rclpy_env: dict[str, str], tmp_path: Path) -> None:
    result = in_netns(_station_script(tmp_path, "", _student(tmp_path, rclpy_env)), 600.0, REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "station exit 0" in result.stderr
    r = json.loads((tmp_path / "report.json").read_text())
    assert {(b["block"], b["tower"], b["height"]) for b in r["final"]["blocks"]} == {(1, 3, 1), (2, 3, 2), (3, 3, 3)}
    assert r["final"]["at_home"] and not r["final"]["suction_on"] and r["commands"]["rejected"] == 0
    durations = [m["duration_s"] for m in r["executed"] if m["duration_s"] > 0]
    assert all(math.isclose(d, 2.0, abs_tol=1e-9) for d in durations)  # the bridge's fixed 2 s moves


def test_enme480_style_rclpy_program_halts_on_a_removed_block(rclpy_env: dict[str, str], tmp_path: Path) -> None:
    result = in_netns(_station_script(tmp_path, "--remove-block 3", _student(tmp_path, rclpy_env)), 300.0, REPO)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Block not found at tower 1 height 3" in result.stderr
    r = json.loads((tmp_path / "report.json").read_text())
    assert r["final"]["at_home"] and not r["final"]["suction_on"]
    assert [e["kind"] for e in r["suction_events"]].count("grasp") == 0


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
