"""What ``rmw_zenoh_cpp`` (ROS 2 Jazzy, rmw_zenoh 0.2; ros2/rmw_zenoh
docs/design.md and src/detail/liveliness_utils.cpp, attachment_helpers.cpp)
puts on zenoh for a publisher, field by field:

- data key expression ``<domain_id>/<topic name without leading and trailing
  slash>/<DDS type name>/<type hash>``, e.g.
  ``0/usv/sub_1/modd_msgs::msg::dds_::Window_/RIHS01_…``;
- payload: CDR with its 4-byte encapsulation header;
- attachment: sequence number (int64), source timestamp (int64, ns) and the
  publisher's GID (16 bytes), in zenoh's serialization (fixed-width little
  endian integers, a byte sequence as a LEB128 length then the bytes): 33 bytes;
- liveliness tokens ``@ros2_lv/<domain_id>/<zid>/<nid>/<id>/<kind>/<enclave>/
  <namespace>/<node name>[/<topic>/<type>/<type hash>/<qos>]`` with ``/``
  replaced by ``%`` inside each part, ``NN`` for the node and ``MP`` for each
  publisher; the QoS part leaves every policy equal to rmw_zenoh's default
  empty (``::,:,:,:,,``: reliable, volatile, keep last).

The GID is 16 bytes of a hash of the publisher's liveliness key expression,
as in rmw_zenoh (which uses XXH3-128; here BLAKE2b-128, equally unique: only
its uniqueness matters to a subscriber).

>>> topic_key(0, "/usv/sub_1", "modd_msgs/msg/Window", "RIHS01_ab")
'0/usv/sub_1/modd_msgs::msg::dds_::Window_/RIHS01_ab'
>>> len(attachment(1, 2, bytes(16)))
33
"""

from __future__ import annotations

import hashlib
import struct

ADMIN_SPACE = "@ros2_lv"
#: Every QoS policy at rmw_zenoh's default (reliable, volatile, keep last).
DEFAULT_QOS = "::,:,:,:,,"
GID_SIZE = 16


def dds_type_name(ros_type: str) -> str:
    """``std_msgs/msg/Float64`` -> ``std_msgs::msg::dds_::Float64_``."""
    package, kind, name = ros_type.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def topic_key(domain_id: int, topic: str, ros_type: str, type_hash: str) -> str:
    return f"{domain_id}/{topic.strip('/')}/{dds_type_name(ros_type)}/{type_hash}"


def mangle(name: str) -> str:
    return name.replace("/", "%")


def node_token(
    domain_id: int, zid: str, node_id: int, node: str, namespace: str = "/", enclave: str = "/"
) -> str:
    return "/".join(
        [
            ADMIN_SPACE,
            str(domain_id),
            zid,
            str(node_id),
            str(node_id),
            "NN",
            mangle(enclave),
            mangle(namespace),
            mangle(node),
        ]
    )


def publisher_token(
    domain_id: int,
    zid: str,
    node_id: int,
    entity_id: int,
    node: str,
    topic: str,
    ros_type: str,
    type_hash: str,
    namespace: str = "/",
    enclave: str = "/",
    qos: str = DEFAULT_QOS,
) -> str:
    return "/".join(
        [
            ADMIN_SPACE,
            str(domain_id),
            zid,
            str(node_id),
            str(entity_id),
            "MP",
            mangle(enclave),
            mangle(namespace),
            mangle(node),
            mangle(topic),
            mangle(dds_type_name(ros_type)),
            mangle(type_hash),
            qos,
        ]
    )


def gid(liveliness_key: str) -> bytes:
    return hashlib.blake2b(liveliness_key.encode(), digest_size=GID_SIZE).digest()


def attachment(sequence_number: int, source_timestamp_ns: int, source_gid: bytes) -> bytes:
    """int64 LE, int64 LE, then the GID as a zenoh byte sequence (length 16
    as one LEB128 byte, the bytes)."""
    if len(source_gid) != GID_SIZE:
        raise ValueError(f"a GID has {GID_SIZE} bytes, not {len(source_gid)}")
    return struct.pack("<qqB", sequence_number, source_timestamp_ns, GID_SIZE) + source_gid
