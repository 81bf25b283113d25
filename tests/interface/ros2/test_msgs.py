"""ur3hanoi.interface.ros2.msgs against an independent implementation: rosbags serializes the course's ``.msg`` text to
CDR and computes RIHS01 hashes. The station's bytes must equal rosbags' for the three course messages (edge cases
included), for std_msgs/Bool and std_msgs/Int32 and for rmw_dds_common's ParticipantEntitiesInfo (Jazzy's 16-byte
Gid); the type hashes are pinned. No DDS participant is created here."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from ur3hanoi.interface.ros2.msgs import (
    MSG_TEXT,
    ROS_TYPES,
    TYPE_HASHES,
    Bool,
    CommandUR3e,
    Gid,
    GripperInput,
    Int32,
    NodeEntitiesInfo,
    ParticipantEntitiesInfo,
    PositionUR3e,
    dds_topic,
)

PINNED = {  # ../shared/lab/ros2-interface.md
    "ur3e_mrc_msgs/msg/CommandUR3e": "RIHS01_2f0dfb5da40b6bad863b59c393cc69c48d7de0c7b9a221e6887242a70a1b9974",
    "ur3e_mrc_msgs/msg/PositionUR3e": "RIHS01_07cb4e678e1673c909c6b9844394c3bd7347c40b95867ecf6a1f10ae424bd745",
    "ur3e_mrc_msgs/msg/GripperInput": "RIHS01_af06f2466c87ef322c22b736462e05003f4dde7867f2bf44ffc965f5ef568841",
    # std_msgs (ur3hanoi/spawn, ur3hanoi/remove_block); the same value is pinned by independent ROS 2 libraries
    "std_msgs/msg/Int32": "RIHS01_b6578ded3c58c626cfe8d1a6fb6e04f706f97e9f03d2727c9ff4e74b1cef0deb",
}


def _store(store: Stores = Stores.ROS2_JAZZY) -> Any:
    ts = get_typestore(store)
    types: dict[str, Any] = {}
    for name, text in MSG_TEXT.items():
        types.update(get_types_from_msg(text, name))
    ts.register(types)
    return ts


TS = _store()


def _oracle(name: str, **fields: Any) -> bytes:
    cls = TS.types[name]
    values = {k: (np.array(v, dtype=np.float64) if isinstance(v, list) else v) for k, v in fields.items()}
    return bytes(TS.serialize_cdr(cls(**values), name))


@pytest.mark.parametrize("store", [Stores.ROS2_HUMBLE, Stores.ROS2_JAZZY, Stores.ROS2_KILTED])
def test_type_hashes_are_pinned_and_rosbags_computes_them(store: Stores) -> None:
    ts = _store(store)
    for name, expected in PINNED.items():
        assert TYPE_HASHES[name] == expected
        assert ts.hash_rihs01(name) == expected
    assert TYPE_HASHES["std_msgs/msg/Bool"] == ts.hash_rihs01("std_msgs/msg/Bool")
    assert set(ROS_TYPES.values()) == set(TYPE_HASHES)


DESTINATIONS = [[], [0.0], [2.0943951023931953, -1.5707963267948966, 1.5707963267948966, -1.5707963267948966,
                              -1.5707963267948966, 0.0], [1e300, -1e-300, -0.0, math.pi, 7.0, -7.0, 3.0]]


@pytest.mark.parametrize("destination", DESTINATIONS)
@pytest.mark.parametrize("io_0", [False, True])
def test_command_bytes_equal_rosbags(destination: list[float], io_0: bool) -> None:
    ours = CommandUR3e(destination=destination, v=4.0, a=-0.5, io_0=io_0).serialize()
    assert ours[:4] == b"\x00\x01\x00\x00"  # plain little-endian CDR
    assert ours == _oracle("ur3e_mrc_msgs/msg/CommandUR3e", destination=destination, v=4.0, a=-0.5, io_0=io_0)
    assert CommandUR3e.deserialize(ours) == CommandUR3e(destination=destination, v=4.0, a=-0.5, io_0=io_0)


@settings(max_examples=50, deadline=None)
@given(st.lists(st.floats(allow_nan=False), max_size=8), st.booleans(),
       st.integers(-2**31, 2**31 - 1), st.floats(allow_nan=False), st.floats(allow_nan=False))
def test_position_and_gripper_bytes_equal_rosbags(position: list[float], ready: bool, dig: int, a0: float,
                                                  a1: float) -> None:
    assert PositionUR3e(position=position, is_ready=ready).serialize() == _oracle(
        "ur3e_mrc_msgs/msg/PositionUR3e", position=position, is_ready=ready)
    assert GripperInput(dig_in=dig, a_in0=a0, a_in1=a1).serialize() == _oracle(
        "ur3e_mrc_msgs/msg/GripperInput", dig_in=dig, a_in0=a0, a_in1=a1)


@settings(max_examples=50, deadline=None)
@given(st.integers(-2**31, 2**31 - 1))
def test_int32_bytes_equal_rosbags(data: int) -> None:
    ours = Int32(data=data).serialize()
    assert ours == bytes(TS.serialize_cdr(TS.types["std_msgs/msg/Int32"](data=data), "std_msgs/msg/Int32"))
    assert Int32.deserialize(ours).data == data
    assert Int32.__idl_typename__ == "std_msgs::msg::dds_::Int32_"


def test_bool_and_discovery_info_bytes_equal_rosbags() -> None:
    assert Bool(data=True).serialize() == bytes(TS.serialize_cdr(TS.types["std_msgs/msg/Bool"](data=True),
                                                                "std_msgs/msg/Bool"))
    T = TS.types
    g = [np.arange(16, dtype=np.uint8), np.arange(16, 32, dtype=np.uint8), np.full(16, 255, dtype=np.uint8)]
    oracle = T["rmw_dds_common/msg/ParticipantEntitiesInfo"](
        gid=T["rmw_dds_common/msg/Gid"](data=g[0]),
        node_entities_info_seq=[T["rmw_dds_common/msg/NodeEntitiesInfo"](
            node_namespace="/", node_name="ur3hanoi_station", reader_gid_seq=[T["rmw_dds_common/msg/Gid"](data=g[1])],
            writer_gid_seq=[T["rmw_dds_common/msg/Gid"](data=g[1]), T["rmw_dds_common/msg/Gid"](data=g[2])])])
    ours = ParticipantEntitiesInfo(
        gid=Gid([int(x) for x in g[0]]),
        node_entities_info_seq=[NodeEntitiesInfo(
            node_namespace="/", node_name="ur3hanoi_station", reader_gid_seq=[Gid([int(x) for x in g[1]])],
            writer_gid_seq=[Gid([int(x) for x in g[1]]), Gid([int(x) for x in g[2]])])])
    assert ours.serialize() == bytes(TS.serialize_cdr(oracle, "rmw_dds_common/msg/ParticipantEntitiesInfo"))


def test_ros_topics_map_to_dds_topics() -> None:
    assert dds_topic("/ur3e/command") == dds_topic("ur3e/command") == "rt/ur3e/command"
    assert CommandUR3e.__idl_typename__ == "ur3e_mrc_msgs::msg::dds_::CommandUR3e_"
