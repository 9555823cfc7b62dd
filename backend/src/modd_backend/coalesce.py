"""An HTTP answer leaves in one send (issue 41).

uvicorn writes an answer's status line and headers, then its body, each at
once: two ``send`` system calls, and on loopback two wake-ups of the client.
On a loaded machine the first write's wake-up often took the CPU from the
event loop with the answer half sent (py-spy under issue 41's load: a third
of the loop's time was in that first write). :class:`CoalescingTransport`
keeps the writes of one event-loop iteration and hands them to the socket
together at the end of it (``writelines``: one ``writev`` with uvloop), so
an answer whose body follows its headers in the same step (every answer
that is not streamed) leaves in one send and wakes its client once.

Nothing waits longer than the current loop iteration; what is kept is at
most what the loop wrote in that iteration; ``close``/``write_eof`` send it
first, ``abort`` drops it, and writes to a closing transport are dropped
(as the transport itself would).

>>> uvicorn.run(app, http=CoalescingHttpToolsProtocol)             # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
from typing import Any

from uvicorn.protocols.http.httptools_impl import HttpToolsProtocol


class CoalescingTransport:
    """``transport``, with the writes of one loop iteration sent as one."""

    __slots__ = ("_transport", "_loop", "_kept", "_due")

    def __init__(self, transport: asyncio.Transport, loop: asyncio.AbstractEventLoop) -> None:
        self._transport = transport
        self._loop = loop
        self._kept: list[bytes] = []
        self._due = False

    def write(self, data: bytes | bytearray | memoryview) -> None:
        if not data:
            return
        # a caller may reuse a bytearray or memoryview once write() returns
        self._kept.append(data if isinstance(data, bytes) else bytes(data))
        if not self._due:
            self._due = True
            self._loop.call_soon(self.flush)

    def writelines(self, lines: Any) -> None:
        for data in lines:
            self.write(data)

    def flush(self) -> None:
        """Send what this iteration wrote (dropped if the transport is closing)."""
        self._due = False
        kept, self._kept = self._kept, []
        if not kept or self._transport.is_closing():
            return
        if len(kept) == 1:
            self._transport.write(kept[0])
        else:
            self._transport.writelines(kept)

    def get_write_buffer_size(self) -> int:
        return self._transport.get_write_buffer_size() + sum(len(b) for b in self._kept)

    def close(self) -> None:
        self.flush()
        self._transport.close()

    def write_eof(self) -> None:
        self.flush()
        self._transport.write_eof()

    def abort(self) -> None:
        self._kept.clear()
        self._transport.abort()

    def __getattr__(self, name: str) -> Any:
        # everything else (get_extra_info, pause_reading, is_closing, set_protocol ...)
        return getattr(self._transport, name)


class CoalescingHttpToolsProtocol(HttpToolsProtocol):
    """uvicorn's httptools protocol over a :class:`CoalescingTransport`
    (``http=`` of uvicorn; a WebSocket upgraded from it writes through it too)."""

    def connection_made(self, transport: asyncio.Transport) -> None:  # type: ignore[override]
        coalescing = CoalescingTransport(transport, asyncio.get_running_loop())
        super().connection_made(coalescing)  # type: ignore[arg-type]
