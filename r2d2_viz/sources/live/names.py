"""ROS 2 ↔ DDS names and the ROS 2 discovery environment, as rmw_cyclonedds maps them (no DDS needed here).

* topic ``/x`` ↔ DDS topic ``rt/x``; type ``pkg/msg/T`` ↔ ``pkg::msg::dds_::T_``;
* ``ROS_DOMAIN_ID`` → the DDS domain (0 when unset);
* ``ROS_AUTOMATIC_DISCOVERY_RANGE`` (``SUBNET`` when unset, ``LOCALHOST`` when not understood — rcl's rules),
  ``ROS_STATIC_PEERS`` (``;``-separated) and the older ``ROS_LOCALHOST_ONLY=1`` (which wins: ``LOCALHOST``, no
  static peers) → a Cyclone DDS XML fragment built like rmw_cyclonedds' ``check_create_domain``;
* ``<Compatibility><IgnoreTypeInformation>1.15</…>``: Fast DDS 3 (Kilted) announces XTypes type information
  Cyclone rejects for some types; ignoring it for eProsima's vendor id falls back to name-based type matching;
* ``<Internal><SocketReceiveBufferSize max="8MB"/>``: ask for an 8 MB UDP receive buffer (the kernel caps it at
  ``net.core.rmem_max``: 208 KiB on a stock kernel, 4 MB here; whatever it gives is accepted). With Cyclone's
  default (the kernel's default buffer, 208 KiB) a 1.2 MB point cloud's fragments overflowed it on a loaded
  machine: 18 of 40 clouds lost in one run, 6 in another, and scans and JPEGs sent beside them.
"""

from __future__ import annotations

import os
import re
from collections.abc import Mapping
from dataclasses import dataclass
from enum import Enum
from xml.sax.saxutils import quoteattr

from r2d2_viz.errors import R2d2VizError, listed


class LiveError(R2d2VizError):
    """The live ROS 2 graph cannot be joined: no cyclonedds, a bad ``ROS_*`` variable, a type we cannot read."""


_TOPIC = re.compile(r"/[A-Za-z0-9_~{}/]*")
_ROS_TYPE = re.compile(r"([A-Za-z][A-Za-z0-9_]*)/(msg|srv|action)/([A-Za-z][A-Za-z0-9_]*)")
_DDS_TYPE = re.compile(r"([A-Za-z][A-Za-z0-9_]*)::(msg|srv|action)::dds_::([A-Za-z][A-Za-z0-9_]*)_")


def dds_topic(topic: str) -> str:
    """``/joint_states`` → ``rt/joint_states`` (a ROS 2 topic's DDS name)."""
    if not _TOPIC.fullmatch(topic) or topic == "/":
        raise LiveError(f"{topic!r} is not a ROS 2 topic name (e.g. /joint_states)")
    return "rt" + topic


def ros_topic(dds_name: str) -> str | None:
    """``rt/joint_states`` → ``/joint_states``; None for a DDS topic that is not a ROS 2 topic."""
    return dds_name[2:] if dds_name.startswith("rt/") and len(dds_name) > 3 else None


def dds_type(ros_type: str) -> str:
    """``sensor_msgs/msg/JointState`` → ``sensor_msgs::msg::dds_::JointState_``."""
    match = _ROS_TYPE.fullmatch(ros_type)
    if not match:
        raise LiveError(f"{ros_type!r} is not a ROS 2 type name (e.g. sensor_msgs/msg/JointState)")
    pkg, kind, name = match.groups()
    return f"{pkg}::{kind}::dds_::{name}_"


def ros_type(dds_name: str) -> str | None:
    """``sensor_msgs::msg::dds_::JointState_`` → ``sensor_msgs/msg/JointState``; None if not a ROS 2 type."""
    match = _DDS_TYPE.fullmatch(dds_name)
    return "/".join(match.groups()) if match else None


FAST_DDS_VENDOR = "1.15"
"""eProsima's RTPS vendor id (0x010f): ``IgnoreTypeInformation`` takes a list of the vendors whose type information
Cyclone should ignore (falling back to name-based type matching, as ROS 2 does anyway)."""
RECEIVE_BUFFER = "8MB"
"""The UDP receive buffer asked of the kernel (Cyclone's ``max``; no ``min``: less is accepted, never an error)."""


EMPTY_GRAPH_HINT = (
    "check that the publishers share ROS_DOMAIN_ID and discovery range (ros2 topic list beside them); "
    "across machines, multicast or ROS_STATIC_PEERS"
)
"""How to check, when a live graph showed nothing (each command adds its own next step)."""
EMPTY_RUN_NEXT = "r2d2-viz --ros --list lists what this machine sees"
"""A live run that received nothing: the quick look at the graph."""
EMPTY_LIST_NEXT = "r2d2-viz --ros keeps waiting for publishers"
"""``--ros --list`` found nothing in its few seconds: the command that keeps waiting."""


class DiscoveryRange(Enum):
    """``ROS_AUTOMATIC_DISCOVERY_RANGE``'s values."""

    OFF = "OFF"
    LOCALHOST = "LOCALHOST"
    SUBNET = "SUBNET"
    SYSTEM_DEFAULT = "SYSTEM_DEFAULT"


@dataclass(frozen=True)
class RosDiscovery:
    """The DDS side of a ROS 2 environment: domain, discovery range, static peers."""

    domain_id: int = 0
    range: DiscoveryRange = DiscoveryRange.SUBNET
    static_peers: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()

    @classmethod
    def from_env(cls, env: Mapping[str, str] | None = None) -> RosDiscovery:
        """Read ``ROS_DOMAIN_ID``, ``ROS_AUTOMATIC_DISCOVERY_RANGE``, ``ROS_STATIC_PEERS``, ``ROS_LOCALHOST_ONLY``."""
        env = os.environ if env is None else env
        warnings: list[str] = []
        raw_domain = env.get("ROS_DOMAIN_ID", "").strip()
        try:
            domain_id = int(raw_domain) if raw_domain else 0
        except ValueError:
            raise LiveError(f"ROS_DOMAIN_ID={raw_domain!r} is not a number (0 to 232)") from None
        if not 0 <= domain_id <= 232:
            raise LiveError(f"ROS_DOMAIN_ID={domain_id} is out of range (0 to 232)")
        if env.get("ROS_LOCALHOST_ONLY", "").strip() == "1":
            return cls(domain_id, DiscoveryRange.LOCALHOST, (), ())
        raw_range = env.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip()
        try:
            discovery = DiscoveryRange(raw_range) if raw_range else DiscoveryRange.SUBNET
        except ValueError:
            warnings.append(f"ROS_AUTOMATIC_DISCOVERY_RANGE={raw_range!r} not understood: LOCALHOST assumed")
            discovery = DiscoveryRange.LOCALHOST
        peers = tuple(p.strip() for p in env.get("ROS_STATIC_PEERS", "").split(";") if p.strip())
        if peers and discovery in (DiscoveryRange.OFF, DiscoveryRange.SYSTEM_DEFAULT):
            warnings.append(f"ROS_STATIC_PEERS ignored: discovery range is {discovery.value}")
            peers = ()
        return cls(domain_id, discovery, peers, tuple(warnings))

    def searched(self) -> str:
        """Where discovery looks, for a line saying that nothing was found there."""
        where = {
            DiscoveryRange.OFF: "this process only",
            DiscoveryRange.LOCALHOST: "this machine only",
            DiscoveryRange.SUBNET: "this machine's networks, by multicast",
            DiscoveryRange.SYSTEM_DEFAULT: "as the DDS configuration says",
        }[self.range]
        peers = f", and the static peers {listed(self.static_peers)}" if self.static_peers else ""
        return f"ROS_DOMAIN_ID {self.domain_id}, discovery range {self.range.value} ({where}{peers})"

    def cyclone_xml(self, pid: int | None = None) -> str:
        """The Cyclone DDS configuration fragment for this environment (``CYCLONEDDS_URI`` is added after it).
        Fast DDS's type information is ignored for every topic, ``ros_discovery_info`` included: Kilted's (Fast
        DDS 3) is one Cyclone rejects ("invalid type object"), and the topic then never matched, so ``--ros --list``
        named no node; Jazzy's (Fast DDS 2.14) matches by name as well."""
        add_localhost = self.range is DiscoveryRange.LOCALHOST
        add_peers = self.range in (DiscoveryRange.LOCALHOST, DiscoveryRange.SUBNET)
        no_multicast = self.range in (DiscoveryRange.LOCALHOST, DiscoveryRange.OFF)
        general = "<General><AllowMulticast>false</AllowMulticast></General>" if no_multicast else ""
        discovery = ""
        if self.range is DiscoveryRange.OFF:
            tag = f"ros_discovery_off_{os.getpid() if pid is None else pid}"
            discovery = f"<Discovery><ParticipantIndex>none</ParticipantIndex><Tag>{tag}</Tag></Discovery>"
        elif no_multicast or (add_peers and self.static_peers):
            peers = ['<Peer address="localhost"/>'] if add_localhost else []
            peers += [f"<Peer address={quoteattr(p)}/>" for p in (self.static_peers if add_peers else ())]
            discovery = (
                "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
                f"<MaxAutoParticipantIndex>32</MaxAutoParticipantIndex><Peers>{''.join(peers)}</Peers></Discovery>"
            )
        compatibility = (
            f"<Compatibility><IgnoreTypeInformation>{FAST_DDS_VENDOR}</IgnoreTypeInformation></Compatibility>"
        )
        internal = f'<Internal><SocketReceiveBufferSize max="{RECEIVE_BUFFER}"/></Internal>'
        return f"<CycloneDDS><Domain>{general}{compatibility}{internal}{discovery}</Domain></CycloneDDS>"
