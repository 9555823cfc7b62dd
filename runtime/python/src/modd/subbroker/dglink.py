"""The link client over datagrams (udp, serial), on its own thread: it opens
the port (:mod:`.dgport`) and pumps a :class:`~.dgsession.DatagramSession`,
behind the same interface as the tcp one (:class:`~.pump.Link`).

>>> session = DatagramSession("udp", key, LinkOptions(), handler)          # doctest: +SKIP
>>> link = DatagramLinkClient(lambda: UdpPort(("127.0.0.1", 7171)), session,
...                           LinkOptions())                             # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from .config import LinkOptions
from .dgport import DatagramPort
from .dgruns import control_frames
from .dgsession import DatagramSession
from .linkhooks import LinkDown
from .pump import Pump

__all__ = ["DatagramLinkClient", "control_frames"]


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
            self.dgram.datagram(raw, source)

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
