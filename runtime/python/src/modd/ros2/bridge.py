"""The bridge: every value the SubBroker delivers (``modd/<drone>/sub/<name>``)
republished as ROS 2 messages on the ROS zenoh network, as ``rmw_zenoh``
publishers of one node (default ``modd_bridge``):

- ``/<drone>/<subscriber>``: ``modd_msgs/msg/Window``;
- ``/<drone>/<subscriber>/value``: ``std_msgs/msg/Float64``;
- ``/<drone>/<subscriber>/backfilled``: ``modd_msgs/msg/Window``, the
  historical windows.

The first two carry live windows only. A backfilled window (filled from the
drone's archive after an outage, delivered late) goes to ``.../backfilled``
alone: the historical mark is the topic, since the Window message has no
field for it (a new field would change its type hash and cut every deployed
``modd_msgs`` off the bridge) and a Float64 has no time at all, so on the
live topics a viewer would take an old value for the current one.

Publishers (and their liveliness tokens, which make them visible to
``ros2 topic list``) are declared on a subscriber's first value, so deploys
and dynamic subscriptions appear by themselves.

>>> b = Ros2Bridge(modd_session, ros_session, drones="usv")   # doctest: +SKIP
>>> b.start()                                                  # doctest: +SKIP
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from modd_contracts import keys
from modd_contracts.delivered import load_delivered
from modd_contracts.types_gen import DeliveredValue

from . import rmw
from .messages import FLOAT64, FLOAT64_HASH, WINDOW, WINDOW_HASH, float64_cdr, window_cdr

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.ros2")
#: The topic under ``/<drone>/<subscriber>`` of the backfilled (historical) windows.
BACKFILLED = "backfilled"


@dataclass
class RosPublisher:
    topic: str
    ros_type: str
    key: str
    token_key: str
    gid: bytes
    publisher: Any
    token: Any
    sequence: int = 0

    def publish(self, payload: bytes) -> None:
        self.sequence += 1
        self.publisher.put(
            payload, attachment=rmw.attachment(self.sequence, time.time_ns(), self.gid)
        )

    def close(self) -> None:
        self.token.undeclare()
        self.publisher.undeclare()


class Ros2Bridge:
    def __init__(
        self,
        modd: zenoh.Session,
        ros: zenoh.Session,
        drones: str = "*",
        domain_id: int = 0,
        node: str = "modd_bridge",
    ) -> None:
        self.modd, self.ros = modd, ros
        self.drones, self.domain_id, self.node = drones, domain_id, node
        #: The values this bridge reads (modd_contracts.keys).
        self.key = keys.values_of(None if drones == "*" else drones)
        self.zid = str(ros.zid())
        self.node_id = 0
        self._next_id = 1
        self._pubs: dict[str, RosPublisher] = {}
        self._lock = threading.Lock()
        self._node_token: Any = None
        self._sub: Any = None
        self.published = 0

    def start(self) -> Ros2Bridge:
        self._node_token = self.ros.liveliness().declare_token(
            rmw.node_token(self.domain_id, self.zid, self.node_id, self.node)
        )
        self._sub = self.modd.declare_subscriber(self.key, self._on_sample)
        return self

    def _publisher(self, topic: str, ros_type: str, type_hash: str) -> RosPublisher:
        with self._lock:
            pub = self._pubs.get(topic)
            if pub is None:
                entity_id, self._next_id = self._next_id, self._next_id + 1
                key = rmw.topic_key(self.domain_id, topic, ros_type, type_hash)
                token_key = rmw.publisher_token(
                    self.domain_id,
                    self.zid,
                    self.node_id,
                    entity_id,
                    self.node,
                    topic,
                    ros_type,
                    type_hash,
                )
                pub = RosPublisher(
                    topic,
                    ros_type,
                    key,
                    token_key,
                    rmw.gid(token_key),
                    self.ros.declare_publisher(key),
                    self.ros.liveliness().declare_token(token_key),
                )
                self._pubs[topic] = pub
                log.info("publishing %s (%s) on %s", topic, ros_type, key)
            return pub

    def _on_sample(self, sample: zenoh.Sample) -> None:
        found = keys.match_sub_key(str(sample.key_expr))
        delivered = load_delivered(sample.payload.to_bytes())
        if found is None or delivered is None:
            return
        self.on_value(*found, delivered)

    def on_value(self, drone: str, subscriber: str, delivered: DeliveredValue) -> None:
        base = f"/{drone}/{subscriber}"
        try:
            window = window_cdr(
                int(delivered["start_ns"]),
                int(delivered["end_ns"]),
                delivered.get("value"),
                delivered.get("count"),
                str(delivered.get("aggregation", "")),
            )
        except (KeyError, TypeError, ValueError) as exc:
            log.warning("%s: value skipped (%s)", base, exc)
            return
        self.published += 1
        if delivered.get("backfilled") is True:  # historical: on its own topic only
            self._publisher(f"{base}/{BACKFILLED}", WINDOW.name, WINDOW_HASH).publish(window)
            return
        self._publisher(base, WINDOW.name, WINDOW_HASH).publish(window)
        self._publisher(f"{base}/value", FLOAT64.name, FLOAT64_HASH).publish(
            float64_cdr(delivered.get("value"))
        )

    def topics(self) -> dict[str, RosPublisher]:
        with self._lock:
            return dict(self._pubs)

    def close(self) -> None:
        if self._sub is not None:
            self._sub.undeclare()
        with self._lock:
            pubs = list(self._pubs.values())
            self._pubs.clear()
        for p in pubs:
            p.close()
        if self._node_token is not None:
            self._node_token.undeclare()
