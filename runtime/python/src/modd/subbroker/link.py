"""The link client over tcp: the base station's side of the MoDD link protocol
(docs/protocol.md), on its own thread.

It connects to the PubBroker (the base station initiates, as in the paper) and
pumps a :class:`~.stream_session.StreamSession`, which proves the pre-shared
key, measures the RTT with PING, has the SubBroker plan
(:meth:`LinkHandler.on_connect`) and sends CONFIG, then hands DATA to the
handler as windows. When the link drops or falls silent it reconnects
(:class:`~.pump.Pump`) and re-establishes the running config (resumes it when
the PubBroker's AUTH_OK still reports it, else sends it again).

>>> link = LinkClient(("127.0.0.1", 7171), key, LinkOptions(), handler)  # doctest: +SKIP
>>> link.start(); link.send_config(config, 5.0)                           # doctest: +SKIP
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Callable

from .backpressure import socket_backlog
from .config import LinkOptions
from .linkhooks import ConfigRejected, LinkDown, LinkHandler, LinkStats
from .pump import Pump
from .roundtrips import RoundTrips
from .stream_session import StreamSession

__all__ = ["ConfigRejected", "LinkClient", "LinkDown", "LinkHandler", "LinkStats", "RoundTrips"]


class LinkClient(Pump):
    """Keeps one authenticated TCP link to the PubBroker up, on a daemon thread."""

    def __init__(
        self,
        endpoint: tuple[str, int],
        key: bytes,
        options: LinkOptions,
        handler: LinkHandler,
        liveness_s: Callable[[], float] = lambda: 3.0,
    ) -> None:
        self.endpoint = endpoint
        self._sock: socket.socket | None = None
        where = f"{endpoint[0]}:{endpoint[1]}"
        self.tcp = StreamSession(key, options, handler, liveness_s, where=where)
        self.tcp.backlog = lambda: socket_backlog(self._sock)
        super().__init__(self.tcp, options, where, "modd-link")

    def _open(self) -> None:
        sock = socket.create_connection(self.endpoint, timeout=self._opt.connect_timeout_s)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock = sock

    def _read(self) -> None:
        sock = self._sock
        if sock is None:
            raise LinkDown("the link is down")
        sock.settimeout(max(0.05, min(0.5, self.tcp.liveness_s() / 4)))
        try:
            data = sock.recv(65536)
        except TimeoutError:
            return
        if not data:
            raise LinkDown("the PubBroker closed the link")
        self.tcp.feed(data)

    def _write(self, data: bytes) -> None:
        sock = self._sock
        if sock is None:
            raise LinkDown("the link is down")
        sock.sendall(data)

    def _close(self, stopping: bool) -> None:
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()
