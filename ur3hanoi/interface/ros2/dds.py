"""A ROS 2 node without ROS: one Cyclone DDS participant speaking ROS 2's conventions.

- **Network**: loopback only by default (:func:`cyclone_config`): Cyclone restricted to ``lo``, multicast off,
  the peer ``127.0.0.1``, so no DDS packet leaves the machine (``../shared/lab/ros2-interface.md``, network
  hygiene). ``network="lab"`` joins the lab network instead: Cyclone's default interface choice and multicast
  discovery, or a named interface. rclpy peers on the same machine find it with
  ``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``.
- **QoS**: every endpoint uses ROS 2's default (depth 10): reliable, volatile, keep last 10, as the course bridge.
- **Type hashes**: each endpoint's USER_DATA carries ``typehash=RIHS01_<hex>;`` (Iron and later read it).
- **Graph**: the node announces its readers and writers on ``ros_discovery_info`` (reliable, transient local,
  keep last 1, 16-byte Gids as on Jazzy and later), so ``ros2 node list`` / rclpy's graph show the node's name.
  Jazzy (rmw_fastrtps 8.4, Fast DDS 2.14) also names each endpoint after it. Kilted (rmw_fastrtps 9.3, Fast DDS
  3.2) lists the node but shows its endpoints as ``_CREATED_BY_BARE_DDS_APP_``: rmw_fastrtps files a discovered
  endpoint under ``participant_guid`` (custom_participant_info.hpp:256), which Fast DDS 3 reads only from
  PID_PARTICIPANT_GUID; Cyclone's SEDP never sends it (the participant is its GUID prefix) and Fast DDS's
  fallback for that case fills only the older ``m_rtps_participant_key`` (Jazzy's source), so every Cyclone
  endpoint lands under the all-zero participant gid (tests/interface/ros2/test_rclpy_interop.py measures it). A second
  entry announced under gid zero names them on Kilted, but then Jazzy and Kilted peers both list the node twice
  and keep a ghost of it after a crash (no participant with gid zero ever leaves): measured, not done.
- Fast DDS 3 (Kilted) announces XTypes information that Cyclone rejects for sequence types unless told to ignore
  eProsima's (vendor 1.15): the config does.
- **Lease**: the participant's lease is :data:`LEASE_DURATION_S` (Cyclone's default is 10 s): a station killed by
  SIGKILL (or a crash) cannot say goodbye, and its peers keep a ghost of it -- a second ``ur3hanoi_station`` in the
  graph, a matched reader that never reads -- until the lease ends. A station restarted at once is thus alone in
  the graph within 3 s. A live participant never comes near it: the station writes every 8 ms, any message renews
  the lease, and Cyclone announces the participant every 0.8 lease (2.4 s) when it is silent; only a process
  frozen for 3 s is dropped, and found again by its next announcement.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any

from ur3hanoi.interface.ros2.msgs import (
    ROS_TYPES,
    TYPE_HASHES,
    Gid,
    NodeEntitiesInfo,
    ParticipantEntitiesInfo,
    dds_topic,
)

LOOPBACK = "loopback"
LAB = "lab"

LEASE_DURATION_S = 3
"""The participant's DDS lease [s]: how long peers keep it after it falls silent (killed, crashed, frozen)."""

_COMPATIBILITY = "<Compatibility><IgnoreTypeInformation>1.15</IgnoreTypeInformation></Compatibility>"


def cyclone_config(network: str = LOOPBACK) -> str:
    """Cyclone DDS configuration XML: ``loopback`` (default), ``lab`` (Cyclone's own interface choice, multicast
    discovery), or the name of one network interface to use with multicast discovery."""
    if network == LOOPBACK:
        general = ('<General><Interfaces><NetworkInterface name="lo"/></Interfaces>'
                   "<AllowMulticast>false</AllowMulticast></General>")
        discovery = ("<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>30</MaxAutoParticipantIndex>"
                     '<Peers><Peer address="127.0.0.1"/></Peers>')
    elif network == LAB:
        general, discovery = "", ""
    else:
        if not network.replace("-", "").replace("_", "").replace(".", "").isalnum():
            raise ValueError(f"network interface {network!r} is invalid: expected loopback, lab or an interface name")
        general = f'<General><Interfaces><NetworkInterface name="{network}"/></Interfaces></General>'
        discovery = ""
    lease = f"<LeaseDuration>{LEASE_DURATION_S} s</LeaseDuration>"
    return (f'<CycloneDDS><Domain id="any">{general}{_COMPATIBILITY}<Discovery>{lease}{discovery}</Discovery>'
            "</Domain></CycloneDDS>")


def domain_id_from_env() -> int:
    """``ROS_DOMAIN_ID`` (0..232, ROS 2's range), default 0."""
    raw = os.environ.get("ROS_DOMAIN_ID", "0") or "0"
    try:
        value = int(raw)
    except ValueError:
        raise ValueError(f"ROS_DOMAIN_ID = {raw!r} is invalid: expected an integer in [0, 232]") from None
    if not 0 <= value <= 232:
        raise ValueError(f"ROS_DOMAIN_ID = {value} is invalid: expected an integer in [0, 232]")
    return value


@dataclass(frozen=True)
class Endpoint:
    """One ROS 2 topic endpoint: ``kind`` "reader" or "writer", the ROS topic, the ROS type name."""

    kind: str
    topic: str
    ros_type: str


class Ros2Node:
    """A ROS 2 node made of one Cyclone DDS participant (see the module docstring).

    Args:
        name: node name (``ur3hanoi_station``).
        domain_id: ROS_DOMAIN_ID.
        network: ``loopback``, ``lab`` or an interface name (:func:`cyclone_config`).
    """

    def __init__(self, name: str, domain_id: int = 0, network: str = LOOPBACK) -> None:
        from cyclonedds.core import Policy, Qos
        from cyclonedds.domain import Domain, DomainParticipant
        from cyclonedds.pub import DataWriter
        from cyclonedds.topic import Topic
        from cyclonedds.util import duration

        self.name = name
        self.domain_id = domain_id
        self.network = network
        self._Qos, self._Policy, self._duration = Qos, Policy, duration
        self._domain = Domain(domain_id, cyclone_config(network))
        self.participant = DomainParticipant(domain_id)
        self._topics: dict[str, Any] = {}
        self.endpoints: list[Endpoint] = []
        self._readers: list[Any] = []
        self._writers: list[Any] = []
        info_qos = Qos(Policy.Reliability.Reliable(duration(seconds=1)), Policy.Durability.TransientLocal,
                       Policy.History.KeepLast(1))
        self._info_writer = DataWriter(self.participant, Topic(self.participant, "ros_discovery_info",
                                                               ParticipantEntitiesInfo), info_qos)

    def _qos(self, ros_type: str) -> Any:
        P = self._Policy
        return self._Qos(P.Reliability.Reliable(self._duration(seconds=1)), P.Durability.Volatile,
                         P.History.KeepLast(10), P.Userdata(f"typehash={TYPE_HASHES[ros_type]};".encode()))

    def _topic(self, ros_topic: str, msg_type: type) -> Any:
        from cyclonedds.topic import Topic

        name = dds_topic(ros_topic)
        if name not in self._topics:
            self._topics[name] = Topic(self.participant, name, msg_type)
        return self._topics[name]

    def publisher(self, ros_topic: str, msg_type: type) -> Any:
        """A DataWriter on ``ros_topic`` with the default ROS 2 QoS and the type's hash."""
        from cyclonedds.pub import DataWriter

        ros_type = ROS_TYPES[msg_type]
        w = DataWriter(self.participant, self._topic(ros_topic, msg_type), self._qos(ros_type))
        self._writers.append(w)
        self.endpoints.append(Endpoint("writer", ros_topic, ros_type))
        return w

    def subscription(self, ros_topic: str, msg_type: type) -> Any:
        """A DataReader on ``ros_topic`` with the default ROS 2 QoS and the type's hash (poll with ``take``)."""
        from cyclonedds.sub import DataReader

        ros_type = ROS_TYPES[msg_type]
        r = DataReader(self.participant, self._topic(ros_topic, msg_type), self._qos(ros_type))
        self._readers.append(r)
        self.endpoints.append(Endpoint("reader", ros_topic, ros_type))
        return r

    def announce(self) -> ParticipantEntitiesInfo:
        """Publish the node's readers and writers on ``ros_discovery_info`` (call after creating them)."""
        info = ParticipantEntitiesInfo(
            gid=Gid(list(self.participant.guid.bytes)),
            node_entities_info_seq=[NodeEntitiesInfo(
                node_namespace="/", node_name=self.name,
                reader_gid_seq=[Gid(list(r.guid.bytes)) for r in self._readers],
                writer_gid_seq=[Gid(list(w.guid.bytes)) for w in self._writers])])
        self._info_writer.write(info)
        return info

    def close(self) -> None:
        """Announce an empty node list and drop every entity (Cyclone deletes them with the participant)."""
        try:
            self._info_writer.write(ParticipantEntitiesInfo(gid=Gid(list(self.participant.guid.bytes))))
        finally:
            self._readers.clear()
            self._writers.clear()
            self._topics.clear()


__all__ = ["LAB", "LOOPBACK", "Endpoint", "Ros2Node", "cyclone_config", "domain_id_from_env"]
