"""The course's ROS 2 messages (package ``ur3e_mrc_msgs``) and the few standard ones, as Cyclone DDS IDL types.

ROS 2 puts a message ``pkg/msg/Name`` on the wire as the DDS type ``pkg::msg::dds_::Name_`` in plain
little-endian CDR (final structs, ``../shared/lab/ros2-interface.md``); a topic ``/ur3e/command`` is the DDS topic
``rt/ur3e/command``. The dataclasses below are those types, written by hand from the ``.msg`` text in
:data:`MSG_TEXT` (the course's files); :data:`TYPE_HASHES` are their RIHS01 hashes (Iron and later), announced in
every endpoint's USER_DATA so the ROS 2 graph shows them. The tests check the CDR bytes and the hashes against
``rosbags``, an independent implementation.

``rmw_dds_common``'s ``ParticipantEntitiesInfo`` is what ROS 2 nodes announce on ``ros_discovery_info`` so that
the graph names a participant's readers and writers after their node (the Gid is 16 bytes on Jazzy and later).
"""


from dataclasses import dataclass, field

from cyclonedds.idl import IdlStruct
from cyclonedds.idl.annotations import final
from cyclonedds.idl.types import array, bounded_str, float64, int32, sequence, uint8

MSG_TEXT: dict[str, str] = {
    "ur3e_mrc_msgs/msg/CommandUR3e": "float64[] destination\nfloat64 v\nfloat64 a\nbool io_0\n",
    "ur3e_mrc_msgs/msg/PositionUR3e": "float64[] position\nbool is_ready\n",
    "ur3e_mrc_msgs/msg/GripperInput": "int32 dig_in\nfloat64 a_in0\nfloat64 a_in1\n",
}
"""The course's ``.msg`` files (ENME480_mrc ``ur3e_mrc_msgs/msg``)."""

TYPE_HASHES: dict[str, str] = {
    "ur3e_mrc_msgs/msg/CommandUR3e": "RIHS01_2f0dfb5da40b6bad863b59c393cc69c48d7de0c7b9a221e6887242a70a1b9974",
    "ur3e_mrc_msgs/msg/PositionUR3e": "RIHS01_07cb4e678e1673c909c6b9844394c3bd7347c40b95867ecf6a1f10ae424bd745",
    "ur3e_mrc_msgs/msg/GripperInput": "RIHS01_af06f2466c87ef322c22b736462e05003f4dde7867f2bf44ffc965f5ef568841",
    "std_msgs/msg/Bool": "RIHS01_feb91e995ff9ebd09c0cb3d2aed18b11077585839fb5db80193b62d74528f6c9",
    "std_msgs/msg/Int32": "RIHS01_b6578ded3c58c626cfe8d1a6fb6e04f706f97e9f03d2727c9ff4e74b1cef0deb",
}
"""RIHS01 type hashes (identical for the Humble, Jazzy and Kilted message stores; pinned by the tests)."""


@dataclass
@final
class CommandUR3e(IdlStruct, typename="ur3e_mrc_msgs::msg::dds_::CommandUR3e_"):  # type: ignore[call-arg]
    """``ur3e/command``: joint ``destination`` [rad, course convention], ``v``, ``a`` (ignored by the bridge),
    suction output ``io_0``."""

    destination: sequence[float64] = field(default_factory=list)
    v: float64 = 0.0
    a: float64 = 0.0
    io_0: bool = False


@dataclass
@final
class PositionUR3e(IdlStruct, typename="ur3e_mrc_msgs::msg::dds_::PositionUR3e_"):  # type: ignore[call-arg]
    """``ur3e/position``: joint angles [rad, course convention]; ``is_ready`` (always true on the course bridge)."""

    position: sequence[float64] = field(default_factory=list)
    is_ready: bool = False


@dataclass
@final
class GripperInput(IdlStruct, typename="ur3e_mrc_msgs::msg::dds_::GripperInput_"):  # type: ignore[call-arg]
    """``ur3e/gripper_input``: ``dig_in`` = digital input 0 (0/1), ``a_in0`` = analog input 0 [V], ``a_in1`` = 0."""

    dig_in: int32 = 0
    a_in0: float64 = 0.0
    a_in1: float64 = 0.0


@dataclass
@final
class Bool(IdlStruct, typename="std_msgs::msg::dds_::Bool_"):  # type: ignore[call-arg]
    """``std_msgs/msg/Bool`` (``gripper/grasping``)."""

    data: bool = False


@dataclass
@final
class Int32(IdlStruct, typename="std_msgs::msg::dds_::Int32_"):  # type: ignore[call-arg]
    """``std_msgs/msg/Int32`` (``ur3hanoi/spawn``: a tower, ``ur3hanoi/remove_block``: a block, numbered from 1)."""

    data: int32 = 0


@dataclass
@final
class Gid(IdlStruct, typename="rmw_dds_common::msg::dds_::Gid_"):  # type: ignore[call-arg]
    """An endpoint's global id: its 16-byte DDS GUID (Jazzy and later)."""

    data: array[uint8, 16] = field(default_factory=lambda: [0] * 16)


@dataclass
@final
class NodeEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::NodeEntitiesInfo_"):  # type: ignore[call-arg]
    """A node's name and its endpoints; the names are ``string<256>`` as in rmw_dds_common's IDL (identical for
    Jazzy's rmw_dds_common 3.1 and Kilted's 4.0)."""

    node_namespace: bounded_str[256] = "/"
    node_name: bounded_str[256] = ""
    reader_gid_seq: sequence[Gid] = field(default_factory=list)
    writer_gid_seq: sequence[Gid] = field(default_factory=list)


@dataclass
@final
class ParticipantEntitiesInfo(IdlStruct, typename="rmw_dds_common::msg::dds_::ParticipantEntitiesInfo_"):  # type: ignore[call-arg]
    """What a participant announces on ``ros_discovery_info``: its Gid and its nodes' readers and writers."""

    gid: Gid = field(default_factory=Gid)
    node_entities_info_seq: sequence[NodeEntitiesInfo] = field(default_factory=list)


ROS_TYPES: dict[type, str] = {CommandUR3e: "ur3e_mrc_msgs/msg/CommandUR3e",
                              PositionUR3e: "ur3e_mrc_msgs/msg/PositionUR3e",
                              GripperInput: "ur3e_mrc_msgs/msg/GripperInput", Bool: "std_msgs/msg/Bool",
                              Int32: "std_msgs/msg/Int32"}
"""The ROS 2 name of each message type the station speaks."""


def dds_topic(ros_topic: str) -> str:
    """The DDS topic of a ROS 2 topic: ``/ur3e/command`` or ``ur3e/command`` -> ``rt/ur3e/command``."""
    return "rt/" + ros_topic.lstrip("/")


__all__ = ["MSG_TEXT", "ROS_TYPES", "TYPE_HASHES", "Bool", "CommandUR3e", "Gid", "GripperInput", "Int32",
           "NodeEntitiesInfo", "ParticipantEntitiesInfo", "PositionUR3e", "dds_topic"]
