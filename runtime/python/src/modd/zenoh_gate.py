"""The accept gate in front of the SubBroker's zenoh listener (docs/security.md,
"Connections per source"): the public ``tcp/`` (or ``tls/``) endpoint is a small TCP
relay that admits a connection only within its source's bounds
(:class:`~modd.zenoh_gate_policy.SourceTable`) and splices it to zenoh's own listener,
moved to a loopback port. A refused connection is sent one line saying why
(:data:`~modd.zenoh_gate_policy.REFUSAL_MARK`), then closed; each throttled source is
logged at most once every :data:`LOG_EVERY_S`.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import re
import socket
import threading
from dataclasses import dataclass, replace

from .ports import free_port
from .zenoh_gate_policy import REFUSAL_MARK, GateLimits, SourceTable, source_of
from .zenoh_session import LISTENER_LIMITS, ZenohSettings

log = logging.getLogger("modd.zenoh_gate")

LOG_EVERY_S = 10.0
CHUNK = 256 * 1024
#: Seconds to reach zenoh's loopback listener before a connection is given up.
UPSTREAM_TIMEOUT_S = 2.0
HINT = 'see the base station\'s docs/security.md, "Connections per source"'
_ENDPOINT = re.compile(r"^(tcp|tls)/(\[[0-9a-fA-F:.]+\]|[^/:?#\[\]]+):(\d+)$")


def parse_gated(endpoint: str) -> tuple[str, str, int] | None:
    """(protocol, host, port) of an endpoint the gate can stand in front of; None for
    another kind (udp/, quic/, ws/, one with #iface or ?metadata)."""
    m = _ENDPOINT.match(endpoint)
    return (m[1], m[2].strip("[]"), int(m[3])) if m else None


@dataclass
class _Conn:
    source: str
    pending: bool = True


class AcceptGate:
    """One public endpoint's gate, on its own thread and asyncio loop."""

    def __init__(
        self,
        public: tuple[str, int],
        upstream: tuple[str, int],
        limits: GateLimits,
        pending_s: float,
    ):
        self.upstream, self.pending_s = upstream, pending_s
        self.table = SourceTable(limits)
        self._sock = socket.create_server(
            public, family=_family(public[0]), backlog=1024, reuse_port=False
        )
        self.address: tuple[str, int] = self._sock.getsockname()[:2]
        self._loop = asyncio.new_event_loop()
        self._thread = threading.Thread(
            target=self._loop.run_forever, name="zenoh-gate", daemon=True
        )
        self._server: asyncio.Server | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._full_logged = float("-inf")

    def start(self) -> AcceptGate:
        self._thread.start()
        serve = asyncio.start_server(self._serve, sock=self._sock, limit=CHUNK)
        self._server = asyncio.run_coroutine_threadsafe(serve, self._loop).result()
        return self

    def stop(self) -> None:
        if not self._thread.is_alive():
            return
        asyncio.run_coroutine_threadsafe(self._shutdown(), self._loop).result(timeout=10)
        self._loop.call_soon_threadsafe(self._loop.stop)
        self._thread.join(timeout=10)
        self._loop.close()

    async def _shutdown(self) -> None:
        if self._server is not None:
            self._server.close()
        for task in list(self._tasks):
            task.cancel()
        await asyncio.gather(*self._tasks, return_exceptions=True)
        await asyncio.sleep(0.05)  # the transports' last callbacks: their sockets closed

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        assert task is not None
        self._tasks.add(task)
        try:
            peer = writer.get_extra_info("peername")
            source = source_of(str(peer[0]) if peer else "?")
            why = self.table.admit(source)
            if why is not None:
                await self._refuse(writer, source, why)
                return
            await self._relay(reader, writer, _Conn(source))
        except asyncio.CancelledError:
            pass  # the gate stops: end quietly (asyncio logs a cancelled connection task)
        except Exception as exc:  # one connection's fault never stops the gate
            log.warning("zenoh gate at %s:%d: a connection failed: %r", *self.address, exc)
        finally:
            self._tasks.discard(task)
            await _close(writer)

    async def _refuse(self, writer: asyncio.StreamWriter, source: str, why: str) -> None:
        n = self.table.due_report(source, LOG_EVERY_S)
        now = self._loop.time()
        if not n and why.startswith("max_sources") and now - self._full_logged >= LOG_EVERY_S:
            n, self._full_logged = 1, now  # the address is not in the table: one line per period
        if n:
            log.warning(
                "zenoh gate at %s:%d: refusing connections from %s (%s); %d refused since "
                "the last line ([zenoh.gate], docs/security.md)",
                *self.address,
                source,
                why,
                n,
            )
        try:
            writer.write(REFUSAL_MARK + f"too many connections: {why}; {HINT}\n".encode())
            writer.write_eof()
            await asyncio.wait_for(writer.drain(), 0.5)
        except (OSError, TimeoutError):
            pass

    async def _relay(
        self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter, conn: _Conn
    ) -> None:
        settle = self._loop.call_later(self.pending_s, self._settle, conn)
        up_writer: asyncio.StreamWriter | None = None
        try:
            connect = asyncio.open_connection(*self.upstream, limit=CHUNK)
            up_reader, up = await asyncio.wait_for(connect, UPSTREAM_TIMEOUT_S)
            up_writer = up
            _nodelay(writer)
            _nodelay(up)
            await _splice(reader, writer, up_reader, up)
        except (OSError, TimeoutError) as exc:
            log.debug("zenoh gate: connection of %s ended: %s", conn.source, exc)
        finally:
            settle.cancel()
            self.table.closed(conn.source, conn.pending)
            if up_writer is not None:
                await _close(up_writer)

    def _settle(self, conn: _Conn) -> None:
        conn.pending = False
        self.table.settled(conn.source)


async def _splice(
    r1: asyncio.StreamReader,
    w1: asyncio.StreamWriter,
    r2: asyncio.StreamReader,
    w2: asyncio.StreamWriter,
) -> None:
    """Copies both ways until either side ends; then both are closed by the caller."""
    pumps = {asyncio.create_task(_pump(r1, w2)), asyncio.create_task(_pump(r2, w1))}
    try:
        await asyncio.wait(pumps, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for p in pumps:
            p.cancel()
        await asyncio.gather(*pumps, return_exceptions=True)


async def _pump(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    try:
        while data := await reader.read(CHUNK):
            writer.write(data)
            await writer.drain()
    except OSError:
        pass


async def _close(writer: asyncio.StreamWriter) -> None:
    writer.close()
    with contextlib.suppress(Exception, asyncio.CancelledError):
        await asyncio.wait_for(writer.wait_closed(), 1.0)


def _nodelay(writer: asyncio.StreamWriter) -> None:
    sock = writer.get_extra_info("socket")
    if sock is not None:
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)


def _family(host: str) -> socket.AddressFamily:
    return socket.AF_INET6 if ":" in host else socket.AF_INET


def start_gates(settings: ZenohSettings) -> tuple[ZenohSettings, list[AcceptGate]]:
    """Puts a gate in front of each ``tcp/``/``tls/`` endpoint ``settings`` listens on
    (its ``gate`` limits enabled): the gate takes the public endpoint, zenoh a free
    loopback port. Returns the settings zenoh is to open with, and the gates to stop
    after its session. Raises ValueError naming an endpoint it cannot listen on."""
    if not settings.listen or not settings.gate.enabled:
        return settings, []
    listen: list[str] = []
    gates: list[AcceptGate] = []
    try:
        for endpoint in settings.listen:
            inner, gate = _gate_one(endpoint, settings)
            listen.append(inner)
            gates += [gate] if gate is not None else []
    except BaseException:
        for gate in gates:
            gate.stop()
        raise
    return replace(settings, listen=tuple(listen)), gates


def _gate_one(endpoint: str, settings: ZenohSettings) -> tuple[str, AcceptGate | None]:
    parsed = parse_gated(endpoint)
    if parsed is None:
        log.warning("zenoh gate: %s is not a tcp/ or tls/ host:port endpoint; not gated", endpoint)
        return endpoint, None
    proto, host, port = parsed
    inner = free_port()
    limits = settings.gate
    try:
        gate = AcceptGate((host, port), ("127.0.0.1", inner), limits, accept_timeout_s(settings))
    except OSError as exc:
        raise ValueError(f"cannot listen on {endpoint}: {exc.strerror or exc}") from exc
    gate.start()
    log.info(
        "zenoh gate on %s (zenoh itself on %s/127.0.0.1:%d): per source at most %d "
        "connections in their handshake, %g new a second",
        endpoint,
        proto,
        inner,
        limits.per_source_pending,
        limits.per_source_rate,
    )
    return f"{proto}/127.0.0.1:{inner}", gate


def accept_timeout_s(settings: ZenohSettings) -> float:
    """The listener's ``accept_timeout``: how long a connection counts as being set up."""
    key = "transport/unicast/accept_timeout"
    try:
        return int(settings.extra.get(key, LISTENER_LIMITS[key])) / 1000.0
    except ValueError:
        return int(LISTENER_LIMITS[key]) / 1000.0
