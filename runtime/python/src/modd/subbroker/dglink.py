"""The link client over datagrams (udp, serial), on its own thread: it opens
the port (:mod:`.dgport`) and pumps a :class:`~.dgsession.DatagramSession`,
behind the same interface as the tcp one (:class:`~.pump.Link`).

>>> session = DatagramSession("udp", key, LinkOptions(), handler)          # doctest: +SKIP
>>> link = DatagramLinkClient(lambda: UdpPort(("127.0.0.1", 7171)), session,
...                           LinkOptions())                             # doctest: +SKIP

Diversity reception (docs/fleet.md): while another station serves the drone, a
station with ``overhear`` set keeps its port open, transmits nothing, and hands what
its modem hears to ``overhear`` (which forwards it to the serving station); the
serving station's :meth:`DatagramLinkClient.relay` takes what the others forward.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

from .config import LinkOptions
from .dgport import DatagramPort
from .dgruns import control_frames
from .dgsession import DatagramSession
from .linkhooks import LinkDown
from .pump import Pump

__all__ = ["DatagramLinkClient", "control_frames"]

log = logging.getLogger("modd.subbroker.dglink")

#: Datagrams other stations forwarded, waiting for the link thread (the oldest go first:
#: seconds of a radio's traffic).
RELAY_QUEUE = 512
#: A listening standby station tells its modem where it is this often (s).
ANNOUNCE_S = 5.0


class DatagramLinkClient(Pump):
    """Keeps one authenticated datagram session with the PubBroker."""

    retry_at_once = False

    def __init__(
        self, open_port: Callable[[], DatagramPort], session: DatagramSession, options: LinkOptions
    ) -> None:
        self.transport = session.transport
        self._open_port = open_port
        self._port: DatagramPort | None = None
        self.dgram = session
        super().__init__(session, options, session.where, "modd-dglink")
        #: While another station serves: what this station's modem hears goes here.
        self.overhear: Callable[[bytes], None] | None = None
        #: given the drone's datagrams this session could not read before it was up (a
        #: takeover's handshake: under the previous station's key; diversity.py)
        self.keep_unread: Callable[[bytes], None] | None = None
        self._relayed: deque[bytes] = deque(maxlen=RELAY_QUEUE)
        self._relay_lock = threading.Lock()
        self._announced = float("-inf")

    @property
    def delay_s(self) -> float:
        return self.dgram.delay_s

    def radio_status(self) -> dict[str, Any]:
        port = self._port
        return self.dgram.radio_status(port.corrupt if port is not None else 0)

    def _open(self) -> None:
        if self._port is None:
            self._port = self._open_port()
        self.dgram.expect(self._port.peer)

    def _read(self) -> None:
        port = self._port
        if port is None:
            raise LinkDown("the link is down")
        if self.dgram.up:  # once the CONFIG is out: the rates are the running link's
            self.dgram.sample_wire(port.wire_in, port.wire_out)
        for raw, source in port.recv(0.05):
            taken = self.dgram.datagram(raw, source)
            keep = self.keep_unread
            if not taken and keep is not None and not self.dgram.up and source == port.peer:
                keep(raw)  # DATA under the previous station's session, before this one is up
        with self._relay_lock:
            relayed, self._relayed = list(self._relayed), deque(maxlen=RELAY_QUEUE)
        for raw in relayed:
            self.dgram.relayed(raw)

    def relay(self, raw: bytes) -> None:
        """A datagram another station's modem heard (any thread): taken by the link
        thread while this station's session is up, else nothing."""
        if self.dgram.up:
            with self._relay_lock:
                self._relayed.append(raw)

    def _while_cut(self) -> None:
        """Another station serves: listen (the port open, nothing sent but the
        announcement) and hand what the drone sends to ``overhear``."""
        overhear = self.overhear
        if overhear is None or not getattr(self.cut, "overhears", False):
            super()._while_cut()
            return
        try:
            if self._port is None:
                self._port = self._open_port()
        except OSError as exc:
            log.warning("listening to %s: %s", self.dgram.where, exc)
            self._stop.wait(1.0)
            return
        port = self._port
        now = time.monotonic()
        if now - self._announced >= ANNOUNCE_S:
            port.announce()
            self._announced = now
        try:
            heard = port.recv(0.1)
        except ConnectionError:  # a serial device that went: opened again next turn
            self._close(stopping=False)
            return
        for raw, source in heard:
            if source == port.peer:  # the drone's radio, not a stranger on the network
                overhear(raw)

    def _write(self, data: bytes) -> None:
        port = self._port
        if port is None:
            raise LinkDown("the link is down")
        port.send(data)

    def _close(self, stopping: bool) -> None:
        if stopping or self.transport == "serial":
            # a serial device is opened again: it may have gone and come back
            port, self._port = self._port, None
            if port is not None:
                port.close()
