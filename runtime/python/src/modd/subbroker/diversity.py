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

It also keeps the last DATA datagrams (at most ``HEARD_KEPT``, ``HEARD_KEPT_BYTES``
bytes): those it heard standing by, those its own session could not read before it was
up (the takeover's handshake) and those other stations forward meanwhile. When the
serving station dies, what the modems heard until this station's session runs was
forwarded to no one or read by no one; the station that takes over reads them under
the dead station's session key (handover.py) and delivers the windows no station holds.

>>> bucket = Bucket(per_s=2, now=0.0)
>>> [bucket.take(0.0), bucket.take(0.0), bucket.take(0.0), bucket.take(0.6)]
[True, True, False, True]
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from typing import TYPE_CHECKING

from modd_contracts.keys import heard_key
from modd_contracts.link_wire_gen import MAX_PACKET

from modd.link.datagram import DGRAM_DATA, DGRAM_DATA_BITMAP, DGRAM_FRAGMENT

from .dglink import DatagramLinkClient

if TYPE_CHECKING:
    import zenoh

log = logging.getLogger("modd.subbroker.diversity")

#: Datagrams a second a standby station forwards at most (a 57,600-baud radio carries
#: about 30 of its largest packets a second; a UDP link's model rates fewer).
MAX_PER_S = 200.0
#: Heard datagrams kept for a takeover: at a radio's ~30 a second, a minute and more.
HEARD_KEPT = 2048
HEARD_KEPT_BYTES = 4 * 1024 * 1024
DATA_KINDS = (DGRAM_DATA, DGRAM_DATA_BITMAP, DGRAM_FRAGMENT)


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
        self._kept: deque[bytes] = deque()
        self._kept_bytes = 0
        self._lock = threading.Lock()
        link.overhear = self.forward
        link.keep_unread = self._keep

    def forward(self, raw: bytes) -> None:
        """A datagram this station's modem heard while another serves (link thread)."""
        if not raw or len(raw) > MAX_PACKET:
            return
        self._keep(raw)
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

    def _keep(self, raw: bytes) -> None:
        if not raw or raw[0] not in DATA_KINDS or len(raw) > MAX_PACKET:
            return
        with self._lock:
            self._kept.append(raw)
            self._kept_bytes += len(raw)
            while len(self._kept) > HEARD_KEPT or self._kept_bytes > HEARD_KEPT_BYTES:
                self._kept_bytes -= len(self._kept.popleft())

    def take_heard(self) -> list[bytes]:
        """The datagrams kept, oldest first, and forget them (read once, at takeover)."""
        with self._lock:
            out = list(self._kept)
            self._kept.clear()
            self._kept_bytes = 0
        return out

    def _on_heard(self, sample: zenoh.Sample) -> None:
        if str(sample.key_expr) == self._own:
            return
        raw = sample.payload.to_bytes()
        if 0 < len(raw) <= MAX_PACKET:
            if self._link.dgram.up:
                self._link.relay(raw)
            else:  # another standby's modem heard it while this station takes over
                self._keep(raw)

    def close(self) -> None:
        self._link.overhear = None
        self._link.keep_unread = None
        self._subscriber.undeclare()  # type: ignore[no-untyped-call]
        self._publisher.undeclare()  # type: ignore[no-untyped-call]
