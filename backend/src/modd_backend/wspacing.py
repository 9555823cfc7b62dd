"""WebSockets parsed a slice at a time, so one flooding client cannot hold
the event loop (and ``/api/health``) while its backlog is parsed.

uvicorn's WebSocket protocol parses every frame of what one socket read
returns (up to 256 KiB: ~4,500 small frames) in one callback: 150-400 ms on
a loaded machine, during which nothing else runs. :class:`PacedWebSocketProtocol`
hands it at most ``CHUNK`` bytes per event-loop iteration and keeps the
socket's reading paused while unparsed bytes wait, so memory stays bounded
(at most one read beyond them) and the kernel's buffers push back on the client.

>>> PacedWebSocketProtocol.CHUNK
4096
"""

from __future__ import annotations

from typing import Any

from uvicorn.protocols.websockets.websockets_sansio_impl import WebSocketsSansIOProtocol


class PacedWebSocketProtocol(WebSocketsSansIOProtocol):
    """uvicorn's sans-I/O WebSocket protocol fed in slices (``ws=`` of uvicorn)."""

    CHUNK = 4096

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self._pending = bytearray()
        self._feeding = False

    def data_received(self, data: bytes) -> None:
        self._pending += data
        if not self._feeding:
            self._feed()

    def _feed(self) -> None:
        self._feeding = False
        if self.disconnected:
            self._pending.clear()
            return
        chunk = bytes(self._pending[: self.CHUNK])
        del self._pending[: self.CHUNK]
        super().data_received(chunk)
        if self._pending:
            self._feeding = True
            self.transport.pause_reading()  # no more until these bytes are parsed
            self.loop.call_soon(self._feed)
        elif not self.read_paused and not self.transport.is_closing():
            self.transport.resume_reading()

    async def receive(self) -> Any:
        message = await super().receive()
        if self._pending and not self.transport.is_closing():
            self.transport.pause_reading()  # the parent resumed: our bytes come first
        return message
