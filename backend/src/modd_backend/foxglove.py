"""The Foxglove WebSocket server of the base station (``foxglove-sdk``):
Foxglove and Lichtblick open ``ws://<host>:<port>`` and see every delivered
value of every drone, live.

Channels: ``/<drone>/<subscriber>`` (one per subscriber, JSON, schema
:data:`WINDOW_SCHEMA`: value, window start/end, sample count, aggregation,
backfilled mark), ``/<drone>/link`` (the SubBroker's status: link state,
RTT, byte rates) and ``/<drone>/position`` (a ``foxglove.LocationFix`` for
the Map panel, from the latitude/longitude subscriptions' live windows). A
backfilled window is logged at its window's end with ``backfilled`` true, so a
plot places it in time and a viewer can tell it from a live value. A channel is
advertised on the first value of its subscriber, so deploys and dynamic
subscriptions appear by themselves, and is withdrawn when the drone's status
no longer routes that subscriber (a new deploy, a cancelled dynamic
subscription).

Contract: :meth:`FoxgloveLive.on_value` and :meth:`FoxgloveLive.on_status`
are zenoh callbacks: they never block (``channel.log`` queues per client in
the SDK, which drops a slow client's oldest data messages first).

The SDK's server has no authentication: the backend runs it on loopback
behind TLS with a certificate only its proxy trusts, and viewers connect
through ``/foxglove/live`` on the backend's own port, with a session
(foxgloveproxy.py, docs/ecosystem.md).

>>> window_message({"value": 1.5, "count": 3, "aggregation": "AVERAGE", "start_ns": 0,
...                 "end_ns": 2_500_000_000})["window_end"]
{'sec': 2, 'nsec': 500000000}
"""

from __future__ import annotations

import json
import logging
import threading
from typing import TYPE_CHECKING, Any

from modd_contracts import aggregations_gen as agg
from modd_contracts.delivered import load_delivered
from modd_contracts.keys import match_status_key, match_sub_key
from modd_contracts.schema import load as contract_schema
from modd_contracts.types_gen import DeliveredValue

from .scene import position_roles
from .viewer_json import as_numbers, for_viewers, without_nulls

if TYPE_CHECKING:
    from .loopback_tls import LoopbackTls

log = logging.getLogger("modd.foxglove")

#: The subprotocol the SDK's server speaks (clients must ask for it).
SUBPROTOCOL = "foxglove.sdk.v1"
#: Default port, as Foxglove's own servers.
DEFAULT_PORT = 8765

_TIME = {"type": "object", "properties": {"sec": {"type": "integer"}, "nsec": {"type": "integer"}}}
# One JSON type per field: Foxglove's and Lichtblick's JSON-schema reader
# (packages/mcap-support parseJsonSchema) refuses a list of types such as
# ["number", "null"] and then drops the whole channel ("Failed to parse channel
# schema"). So a null is left out of the message (viewer_json.py), and every
# message validates against its channel's schema.


def window_schema(aggregation: str = "") -> dict[str, Any]:
    """The ``modd.Window`` schema of a subscriber: ``value`` is an array of
    numbers for ``ALL``, a number otherwise (null for an empty window)."""
    value: dict[str, Any] = (
        {
            "description": "the window's samples (true/false as 1/0); absent for an empty window",
            "type": "array",
            "items": {"type": "number"},
        }
        if aggregation == agg.ALL
        else {
            "description": "the aggregate (true/false as 1/0); absent for an empty window",
            "type": "number",
        }
    )
    return {
        "title": "modd.Window",
        "description": "One window of a MoDD subscription (docs/subbroker.md, delivered value)",
        "type": "object",
        "properties": {
            "value": value,
            "count": {
                "description": "samples in the window (AVERAGE, COUNT, ALL); absent "
                "when the drone does not send it (MIN, MAX, LAST)",
                "type": "integer",
            },
            "aggregation": {"type": "string"},
            "window_start": _TIME,
            "window_end": _TIME,
            "backfilled": {"description": "delivered late, after a link outage", "type": "boolean"},
            "topic": {"type": "string"},
            "period_s": {"type": "string"},
            "unit": {"type": "string"},
            "delivered": _TIME,
        },
        "required": [
            "aggregation",
            "window_start",
            "window_end",
            "backfilled",
            "topic",
            "period_s",
            "unit",
            "delivered",
        ],
        "additionalProperties": False,
    }


WINDOW_SCHEMA: dict[str, Any] = window_schema()
#: foxglove.LocationFix (the Map panel's message), JSON-encoded.
LOCATION_SCHEMA: dict[str, Any] = {
    "title": "foxglove.LocationFix",
    "type": "object",
    "properties": {
        "timestamp": _TIME,
        "frame_id": {"type": "string"},
        "latitude": {"type": "number"},
        "longitude": {"type": "number"},
        "altitude": {"type": "number"},
        "position_covariance": {"type": "array", "items": {"type": "number"}},
        "position_covariance_type": {"type": "integer"},
    },
}
#: The SubBroker's status contract (status.schema.json) as the viewers read it:
#: every field declared (a null is left out of the message).
LINK_SCHEMA: dict[str, Any] = {**for_viewers(contract_schema("status")), "title": "modd.LinkStatus"}


def _time(ns: int) -> dict[str, int]:
    """Times travel as ``{sec, nsec}`` (Foxglove's time type): a nanosecond
    count since 1970 does not fit a JavaScript number exactly."""
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def window_message(delivered: DeliveredValue) -> dict[str, Any]:
    """The Foxglove message of one delivered value (docs/subbroker.md)."""
    start = int(delivered.get("start_ns") or 0)
    end = int(delivered.get("end_ns") or 0)
    value, count = as_numbers(delivered.get("value")), delivered.get("count")
    message: dict[str, Any] = without_nulls(
        {
            "value": value,
            "count": count if isinstance(count, int) and not isinstance(count, bool) else None,
            "aggregation": delivered.get("aggregation", ""),
            "window_start": _time(start),
            "window_end": _time(end),
            "backfilled": bool(delivered.get("backfilled", False)),
            "topic": delivered.get("topic", ""),
            "period_s": str(delivered.get("period_s", "")),
            "unit": delivered.get("unit", ""),
            "delivered": _time(int(delivered.get("delivered_ns") or 0)),
        }
    )
    return message


def routed_subscribers(status: dict[str, Any]) -> set[str] | None:
    """Subscribers a status says are delivered (routes and dynamic ones);
    None when the status does not say (then nothing is withdrawn)."""
    routes = status.get("routes")
    if not isinstance(routes, dict):
        return None
    out = {str(s) for names in routes.values() if isinstance(names, list) for s in names}
    dynamic = status.get("dynamic")
    if isinstance(dynamic, list):
        out.update(str(d) for d in dynamic)
    return out


class FoxgloveLive:
    """A Foxglove server on ``host:port`` fed with delivered values and
    statuses (``modd/*/sub/*``, ``modd/*/status``) by the backend's zenoh
    session. ``port`` 0 picks a free port (:attr:`port` says which). With
    ``tls`` it speaks ``wss://`` only: the backend runs it so on loopback,
    reached through its authenticated proxy (foxgloveproxy.py)."""

    def __init__(
        self, host: str, port: int, name: str = "MoDD base station", tls: LoopbackTls | None = None
    ) -> None:
        import foxglove

        self._foxglove = foxglove
        self.context = foxglove.Context()
        self.server = foxglove.start_server(
            name=name,
            host=host,
            port=port,
            context=self.context,
            tls_cert=tls.cert_pem if tls else None,
            tls_key=tls.key_pem if tls else None,
        )
        self.host = host
        self.port = self.server.port
        self._channels: dict[str, Any] = {}
        self._schemas: dict[str, bytes] = {}  # topic -> the schema advertised
        self._fix: dict[str, dict[str, float]] = {}  # drone -> lat/lon/alt seen last
        self._lock = threading.Lock()
        self.logged = 0

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"ws://{host}:{self.port}"

    def topics(self) -> list[str]:
        with self._lock:
            return sorted(self._channels)

    def _channel(self, topic: str, schema: dict[str, Any], title: str) -> Any:
        """The channel of ``topic``; advertised again when its schema changes
        (a new deploy made a subscriber ``ALL``, or no longer)."""
        data = json.dumps(schema).encode()
        with self._lock:
            ch = self._channels.get(topic)
            if ch is not None and self._schemas.get(topic) != data:
                ch.close()  # withdrawn before its successor is advertised
                ch = None
            if ch is None:
                fg = self._foxglove
                ch = fg.Channel(
                    topic,
                    message_encoding="json",
                    context=self.context,
                    schema=fg.Schema(name=title, encoding="jsonschema", data=data),
                )
                self._channels[topic] = ch
                self._schemas[topic] = data
            return ch

    def on_value(self, key: str, payload: bytes) -> None:
        """zenoh callback for ``modd/<drone>/sub/<subscriber>``."""
        found = match_sub_key(key)
        delivered = load_delivered(payload)
        if found is None or delivered is None:
            return
        drone, subscriber = found
        msg = window_message(delivered)
        ch = self._channel(
            f"/{drone}/{subscriber}",
            window_schema(str(delivered.get("aggregation", ""))),
            "modd.Window",
        )
        end_ns = int(delivered.get("end_ns") or 0)
        ch.log(msg, log_time=end_ns or None)
        self.logged += 1
        self._position(drone, subscriber, delivered, end_ns)

    def _position(
        self, drone: str, subscriber: str, delivered: DeliveredValue, end_ns: int
    ) -> None:
        """``/<drone>/position`` (LocationFix) from the subscriptions whose
        topic is a latitude, longitude or altitude (the 3D scene's rule). A
        backfilled (historical) window is left out: a LocationFix has no field
        to mark it, the Map panel would take it for where the drone is now, and
        it would pair an old latitude with a live longitude."""
        if delivered.get("backfilled") is True:
            return
        role = position_roles(
            {"subscribers": [{"name": subscriber, "topic": delivered.get("topic", "")}]}
        ).get(subscriber)
        value = delivered.get("value")
        if (
            role not in ("lat", "lon", "alt")
            or isinstance(value, bool)
            or not isinstance(value, int | float)
        ):
            return
        with self._lock:
            fix = self._fix.setdefault(drone, {})
            fix[role] = float(value)
            if role == "alt" or "lat" not in fix or "lon" not in fix:
                return
            lat, lon, alt = fix.pop("lat"), fix.pop("lon"), fix.get("alt", 0.0)
        ch = self._channel(f"/{drone}/position", LOCATION_SCHEMA, "foxglove.LocationFix")
        ch.log(
            {
                "timestamp": _time(end_ns),
                "frame_id": drone,
                "latitude": lat,
                "longitude": lon,
                "altitude": alt,
                "position_covariance": [0.0] * 9,
                "position_covariance_type": 0,
            },
            log_time=end_ns or None,
        )

    def on_status(self, key: str, payload: bytes) -> None:
        """zenoh callback for ``modd/<drone>/status``: the link channel, and
        withdraws the channels of subscribers no longer routed."""
        drone = match_status_key(key)
        status = _load(payload)
        if drone is None or status is None:
            return
        time_ns = status.get("time_ns")
        link = self._channel(f"/{drone}/link", LINK_SCHEMA, "modd.LinkStatus")
        link.log(without_nulls(status), log_time=time_ns if isinstance(time_ns, int) else None)
        routed = routed_subscribers(status)
        if routed is None:
            return
        prefix = f"/{drone}/"
        with self._lock:
            gone = [
                t
                for t in self._channels
                if t.startswith(prefix) and t[len(prefix) :] not in routed | {"link", "position"}
            ]
            closing = [self._channels.pop(t) for t in gone]
            for t in gone:
                self._schemas.pop(t, None)
        for ch in closing:
            ch.close()

    def stop(self) -> None:
        with self._lock:
            channels = list(self._channels.values())
            self._channels.clear()
            self._schemas.clear()
        for ch in channels:
            ch.close()
        self.server.stop()


def _load(payload: bytes) -> dict[str, Any] | None:
    try:
        data = json.loads(payload)
    except (ValueError, UnicodeDecodeError):
        return None
    return data if isinstance(data, dict) else None
