"""ros2-station against a real rclpy (ROS 2 Jazzy and Kilted wheels from PyPI, Fast-RTPS 2.14 / Fast DDS 3.2, each in
the environment ``ur3hanoi ros2-env`` builds, tests/support/rclpy_support.py), everything inside a private network
namespace:
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

from tests.support import SUPPORT
from tests.support.rclpy_support import DISTROS, PeerEnv, build_env
from tests.support.ros2_support import NETNS_PROBLEM, REPO, in_netns
from ur3hanoi.interface.ros2.msgs import TYPE_HASHES
from ur3hanoi.robot.convention import from_controller
from ur3hanoi.station.calibration import load_station

pytestmark = [pytest.mark.rclpy, pytest.mark.skipif(NETNS_PROBLEM is not None, reason=NETNS_PROBLEM or "")]


@pytest.fixture(scope="module", params=sorted(DISTROS))
def rclpy_env(request: pytest.FixtureRequest) -> PeerEnv:
    return build_env(request.param)


def _station(tmp_path: Path, station_args: str = "") -> str:
    """The shell line starting ``ros2-station`` in the background (output in ``tmp_path``)."""
    out = f"--report {tmp_path}/report.json > {tmp_path}/st.out 2> {tmp_path}/st.err"
    return f"$UR3HANOI ros2-station {station_args} {out} &"


def _station_script(tmp_path: Path, launch: str, peer: str) -> str:
    """Start ``launch`` (a background shell line writing ``tmp_path/st.out`` and ``st.err``, where its ready line
    goes), wait for its ready line, run ``peer``,
    stop the station with SIGINT; exit with the peer's code."""
    return f"""
{launch}
ST=$!
wait_ready {tmp_path}/st.err || exit 90
{peer}
CODE=$?
kill -INT $ST; wait $ST; echo "station exit $?" >&2
exit $CODE
"""


def _probe(rclpy_env: PeerEnv, tmp_path: Path, launch: str) -> dict[str, Any]:
    """The graph an rclpy peer sees (tests/support/rclpy_graph_probe.py) while ``launch`` runs (see
    :func:`_station_script`)."""
    result = in_netns(_station_script(tmp_path, launch, rclpy_env.peer_command(str(SUPPORT / "rclpy_graph_probe.py"))),
                      180.0, REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    graph: dict[str, Any] = json.loads(result.stdout.strip().splitlines()[-1])
    return graph


@pytest.fixture(scope="module")
def graph(rclpy_env: PeerEnv, tmp_path_factory: pytest.TempPathFactory) -> dict[str, Any]:
    """What the rclpy peer's graph says about ``ros2-station`` (one station run per distro)."""
    tmp_path = tmp_path_factory.mktemp(f"graph-{rclpy_env.distro}")
    return _probe(rclpy_env, tmp_path, _station(tmp_path))


def _endpoint_nodes(graph: dict[str, Any]) -> set[str]:
    return {e["node"] for v in [*graph["publishers"].values(), *graph["subscriptions"].values()] for e in v}


def test_graph_lists_the_node(graph: dict[str, Any]) -> None:
    """Both distros take the station's ros_discovery_info sample: its node is listed, once."""
    assert graph["nodes"].count("ur3hanoi_station") == 1


KILTED_GAP = ("Fast DDS 3.2 never sets participant_guid for Cyclone's endpoints (Cyclone's SEDP has no "
              "PID_PARTICIPANT_GUID; Fast DDS's fallback fills only m_rtps_participant_key) and rmw_fastrtps 9.3 "
              "(custom_participant_info.hpp:256) keys each endpoint by proxyData.participant_guid: Kilted files "
              "every Cyclone endpoint under the all-zero participant gid, where no ros_discovery_info entry can "
              "name it without listing the node twice (see test_kilted_files_cyclone_endpoints_under_gid_zero)")


def test_graph_names_the_nodes_endpoints(rclpy_env: PeerEnv, graph: dict[str, Any],
                                         request: pytest.FixtureRequest) -> None:
    """Jazzy names the station's four endpoints after ur3hanoi_station; Kilted shows them as
    _CREATED_BY_BARE_DDS_APP_ (:data:`KILTED_GAP`), a known gap kept visible as a strict xfail."""
    if rclpy_env.distro == "kilted":
        request.applymarker(pytest.mark.xfail(strict=True, reason=KILTED_GAP))
    assert _endpoint_nodes(graph) == {"ur3hanoi_station"}


# A Cyclone node like the station (ur3hanoi.interface.ros2.dds.Ros2Node) that announces its endpoints on
# ros_discovery_info under the all-zero participant gid instead of its own.
_GID_ZERO_NODE = """
import signal
import sys
import time
from cyclonedds.core import Policy, Qos
from cyclonedds.pub import DataWriter
from cyclonedds.topic import Topic
from cyclonedds.util import duration
from ur3hanoi.interface.ros2.dds import Ros2Node
from ur3hanoi.interface.ros2.msgs import Gid, GripperInput, NodeEntitiesInfo, ParticipantEntitiesInfo, PositionUR3e
node = Ros2Node("ur3hanoi_station")
position = node.publisher("ur3e/position", PositionUR3e)
gripper = node.publisher("ur3e/gripper_input", GripperInput)
qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.TransientLocal,
          Policy.History.KeepLast(1))
info = DataWriter(node.participant, Topic(node.participant, "ros_discovery_info", ParticipantEntitiesInfo), qos)
info.write(ParticipantEntitiesInfo(gid=Gid([0] * 16), node_entities_info_seq=[NodeEntitiesInfo(
    node_namespace="/", node_name="ur3hanoi_station",
    writer_gid_seq=[Gid(list(w.guid.bytes)) for w in (position, gripper)])]))
signal.signal(signal.SIGINT, signal.default_int_handler)  # a background job of a script starts with SIGINT ignored
print("ros2-station: ready", file=sys.stderr, flush=True)
try:
    while True:
        position.write(PositionUR3e(position=[0.0] * 6, is_ready=True))
        gripper.write(GripperInput())
        time.sleep(0.1)
except KeyboardInterrupt:
    pass
"""


def test_kilted_files_cyclone_endpoints_under_gid_zero(rclpy_env: PeerEnv, tmp_path: Path) -> None:
    """The measured cause of :data:`KILTED_GAP`: a ros_discovery_info entry whose gid is all zeros names a Cyclone
    node's endpoints on Kilted, not on Jazzy (which files them under the real participant gid, the GUID prefix
    with entity id 0x1c1). If a Fast DDS release fills participant_guid from the endpoint GUID, the Kilted half
    fails here and the strict xfail above turns XPASS."""
    node = f"{shlex.quote(sys.executable)} -c {shlex.quote(_GID_ZERO_NODE)} > {tmp_path}/st.out 2> {tmp_path}/st.err &"
    graph = _probe(rclpy_env, tmp_path, node)
    expected = "ur3hanoi_station" if rclpy_env.distro == "kilted" else "_CREATED_BY_BARE_DDS_APP_"
    assert {e["node"] for v in graph["publishers"].values() for e in v} == {expected}


def test_graph_shows_topics_types_hashes_and_qos(graph: dict[str, Any]) -> None:
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


def _student(tmp_path: Path, env: PeerEnv, blocks: int = 3) -> str:
    table = tmp_path / "lab2_data.yaml"
    from ur3hanoi import cli

    assert cli.main(["tables", "ur3e_sim", "--key", "sim_pos", "-o", str(table), "--convention", "course"]) == 0
    home = from_controller(np.array(load_station("ur3e_sim").q_home), "course")
    return env.peer_command(str(SUPPORT / "enme480_student.py"), str(table), "1", "3",
                            ",".join(repr(float(x)) for x in home), str(blocks))


def test_enme480_style_rclpy_program_solves_1_to_3(rclpy_env: PeerEnv, tmp_path: Path) -> None:
    """Two blocks (3 moves of about 6 bridge moves of 2 s each): a pick from a stack, a place on an empty tower and
    one on a block, as the lab's 3 blocks do (those took 100 s per distribution; the missing block at height 3 is
    the next test's)."""
    script = _station_script(tmp_path, _station(tmp_path, "--blocks 2"), _student(tmp_path, rclpy_env, 2))
    result = in_netns(script, 600.0, REPO)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "station exit 0" in result.stderr
    r = json.loads((tmp_path / "report.json").read_text())
    assert {(b["block"], b["tower"], b["height"]) for b in r["final"]["blocks"]} == {(1, 3, 1), (2, 3, 2)}
    assert [e["kind"] for e in r["suction_events"]].count("grasp") == 3
    assert r["final"]["at_home"] and not r["final"]["suction_on"] and r["commands"]["rejected"] == 0
    durations = [m["duration_s"] for m in r["executed"] if m["duration_s"] > 0]
    assert all(math.isclose(d, 2.0, abs_tol=1e-9) for d in durations)  # the bridge's fixed 2 s moves


def test_enme480_style_rclpy_program_halts_on_a_removed_block(rclpy_env: PeerEnv, tmp_path: Path) -> None:
    script = _station_script(tmp_path, _station(tmp_path, "--remove-block 3"), _student(tmp_path, rclpy_env))
    result = in_netns(script, 300.0, REPO)
    assert result.returncode == 1, result.stdout + result.stderr
    assert "Block not found at tower 1 height 3" in result.stderr
    r = json.loads((tmp_path / "report.json").read_text())
    assert r["final"]["at_home"] and not r["final"]["suction_on"]
    assert [e["kind"] for e in r["suction_events"]].count("grasp") == 0


if __name__ == "__main__":
    sys.exit(pytest.main([__file__, "-q"]))
