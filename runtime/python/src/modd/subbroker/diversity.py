"""Diversity reception (docs/fleet.md): every station that hears a drone on a shared
radio channel gives the serving station what its modem heard, as the gateways of a
LoRaWAN network give every frame to its network server. The serving station verifies
each under its session key and takes what its own modem missed; what both heard is
a copy and is dropped. So a window either station's modem got is delivered live, and
is never left for a backfill.

A standby station puts each datagram on ``modd/<drone>/fleet/heard/<station>``
(:func:`~modd_contracts.keys.heard_key`), at most ``MAX_PER_S`` a second (a radio's
rate is far below: more is a flood, dropped and counted); every station subscribes to
the others' and hands them to its link (taken only while its session is up).

>>> bucket = Bucket(per_s=2, now=0.0)
>>> [bucket.take(0.0), bucket.take(0.0), bucket.take(0.0), bucket.take(0.6)]
[True, True, False, True]
"""

from __future__ import annotations

import logging
import time
from typing import TYPE_CHECKING

from modd_contracts.keys import heard_key
from modd_contracts.link_wire_gen import MAX_PACKET

from .dglink import DatagramLinkClient

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.diversity")

#: Datagrams a second a standby station forwards at most (a 57,600-baud radio carries
#: about 30 of its largest packets a second; a UDP link's model rates fewer).
MAX_PER_S = 200.0


class Bucket:
    """A token bucket of ``per_s`` a second, as deep as one second."""

    def __init__(self, per_s: float, now: float) -> None:
        self.per_s = per_s
        self._tokens = per_s
        self._at = now

    def take(self, now: float) -> bool:
        self._tokens = min(self.per_s, self._tokens + (now - self._at) * self.per_s)
        self._at = now
        if self._tokens < 1.0:
            return False
        self._tokens -= 1.0
        return True


class Diversity:
    """One station's side: forward what its modem hears while it stands by, and
    hand its link what the others forward."""

    def __init__(
        self, session: zenoh.Session, drone: str, station: str, link: DatagramLinkClient
    ) -> None:
        self.station = station
        self.forwarded = 0
        self.flooded = 0
        self._bucket = Bucket(MAX_PER_S, time.monotonic())
        self._publisher = session.declare_publisher(heard_key(drone, station))
        self._own = heard_key(drone, station)
        self._link = link
        self._subscriber = session.declare_subscriber(heard_key(drone, None), self._on_heard)
        link.overhear = self.forward

    def forward(self, raw: bytes) -> None:
        """A datagram this station's modem heard while another serves (link thread)."""
        if not raw or len(raw) > MAX_PACKET:
            return
        if not self._bucket.take(time.monotonic()):
            self.flooded += 1
            if self.flooded % 1000 == 1:
                log.warning(
                    "station %s: %d heard datagrams over %g/s not forwarded",
                    self.station,
                    self.flooded,
                    MAX_PER_S,
                )
            return
        self._publisher.put(raw)
        self.forwarded += 1

    def _on_heard(self, sample: zenoh.Sample) -> None:
        if str(sample.key_expr) == self._own:
            return
        raw = sample.payload.to_bytes()
        if 0 < len(raw) <= MAX_PACKET:
            self._link.relay(raw)

    def close(self) -> None:
        self._link.overhear = None
        self._subscriber.undeclare()  # type: ignore[no-untyped-call]
        self._publisher.undeclare()  # type: ignore[no-untyped-call]
