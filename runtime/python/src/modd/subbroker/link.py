"""The link client: the base station's side of the MoDD link protocol
(docs/protocol.md), on its own thread.

It connects to the PubBroker (the base station initiates, as in the paper),
proves the pre-shared key, measures the RTT with PING, has the SubBroker
plan (:meth:`LinkHandler.on_connect`) and sends CONFIG, then reads frames:
DATA goes through the codec's :class:`~modd.link.receiver.Receiver` to the
handler as windows; CONFIG_ACK, PONG, STATUS and ERROR are handled here.
When the link drops or falls silent it reconnects: at once the first time
after a link that was up, then with exponential backoff; it re-establishes
the running config (resumes it when the PubBroker's AUTH_OK still reports it, else sends it again).

Silence: after half the liveness timeout without a frame it sends one PING;
after the whole timeout it drops the connection. Nothing else is sent while
DATA flows, so that the link stays as quiet as the plan predicts, unless
``ping_period_s`` asks for periodic PINGs (:class:`RoundTrips`) that keep the
measured RTT current.
"""

from __future__ import annotations

import contextlib
import logging
import os
import socket
import statistics
import struct
import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field
from typing import Protocol

from modd.link import backfill as bf
from modd.link import codec
from modd.link.auth import client_handshake
from modd.link.frames import (
    AuthOk,
    Config,
    ConfigAck,
    ErrorCode,
    ErrorMsg,
    Ping,
    Pong,
    ProtocolError,
    Status,
)
from modd.link.receiver import Receiver, Window

from .backpressure import Backpressure, socket_backlog
from .config import LinkOptions

log = logging.getLogger("modd.subbroker.link")


class LinkDown(ConnectionError):
    """The link is not up (or dropped while waiting)."""


class ConfigRejected(RuntimeError):
    """The PubBroker refused a CONFIG; ``status`` is its CONFIG_ACK status or ERROR code."""

    def __init__(self, status: int, message: str) -> None:
        super().__init__(message)
        self.status = status


class LinkHandler(Protocol):
    """What the SubBroker does with link events (called on the link thread)."""

    def on_connect(self, ok: AuthOk, rtt_s: float | None) -> Config | None:
        """The CONFIG to send now, or None to resume the one ``ok`` reports."""
        ...

    def on_config_acked(self, config: Config, ack: ConfigAck) -> None: ...

    def on_windows(self, windows: list[Window]) -> None: ...

    def on_status(self, status: Status) -> None: ...


class RoundTrips:
    """The periodic PINGs of an established link (``[link] ping_period_s``) and the
    round trips their PONGs measure: the link's RTT follows a radio whose latency
    changes (the NACK timing and the next plan use it). At most ``in_flight``
    PINGs are awaited; older ones are forgotten (a lost PING costs nothing)."""

    def __init__(self, period_s: float, keep: int = 5, in_flight: int = 4) -> None:
        self.period_s = period_s
        self._keep = keep
        self._in_flight = in_flight
        self._sent: dict[bytes, float] = {}
        self._recent: list[float] = []
        self._next = 0.0
        self._count = 0

    def restart(self, now: float) -> None:
        """A new session: the first periodic PING one period from now."""
        self._sent.clear()
        self._next = now + self.period_s

    def due(self, now: float) -> bytes | None:
        """The payload of the PING to send now, or None (periodic PINGs off, or not yet)."""
        if self.period_s <= 0 or now < self._next:
            return None
        self._next = now + self.period_s
        self._count += 1
        payload = b"rt" + struct.pack("<I", self._count & 0xFFFFFFFF) + os.urandom(2)
        self._sent[payload] = now
        while len(self._sent) > self._in_flight:
            del self._sent[next(iter(self._sent))]
        return payload

    def on_pong(self, payload: bytes, now: float) -> float | None:
        """The median of the recent round trips once this PONG answers one of ours."""
        start = self._sent.pop(payload, None)
        if start is None:
            return None
        self._recent = [*self._recent[1 - self._keep:], now - start]
        return statistics.median(self._recent)


@dataclass
class LinkStats:
    """Counters of the link as the SubBroker sees it (frame bytes, not IP)."""

    state: str = "connecting"
    bytes_in: int = 0
    bytes_out: int = 0
    frames_in: int = 0
    data_frames: int = 0
    bad_frames: int = 0
    connects: int = 0
    rtt_s: float | None = None
    last_data_ns: int | None = None
    last_error: str | None = None
    pubbroker: dict[str, int] = field(default_factory=dict)
    backpressure: Backpressure = field(default_factory=Backpressure)


@dataclass
class _Pending:
    config: Config
    future: Future[ConfigAck]
    deadline: float
    connecting: bool  # sent on connect: no ack in time drops the link


class LinkClient:
    """Keeps one authenticated link to the PubBroker up, on a daemon thread."""

    def __init__(
        self,
        endpoint: tuple[str, int],
        key: bytes,
        options: LinkOptions,
        handler: LinkHandler,
        liveness_s: Callable[[], float] = lambda: 3.0,
    ) -> None:
        self.endpoint = endpoint
        self._key = key
        self._opt = options
        self._handler = handler
        self._liveness_s = liveness_s
        self.stats = LinkStats()
        self.receiver = Receiver()
        self._sock: socket.socket | None = None
        self._splitter: codec.FrameSplitter | None = None
        self._send_lock = threading.Lock()
        self._pending: dict[int, _Pending] = {}
        self._round_trips = RoundTrips(options.ping_period_s)
        self._up = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="modd-link", daemon=True)
        #: Backfill frames from the PubBroker go here (link thread); ``on_up`` runs after each
        #: (re)connection, so that running backfills are asked for again with their resume point.
        self.backfill_sink: Callable[[codec.RawFrame], None] | None = None
        self.on_up: Callable[[], None] | None = None

    # -- public --------------------------------------------------------------

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._drop("stopping")
        self._thread.join(timeout=5.0)

    @property
    def up(self) -> bool:
        return self._up.is_set()

    def send_frame(self, frame: bytes) -> None:
        """Send one encoded frame (a backfill request or cancel); raises LinkDown."""
        if not self._up.is_set():
            raise LinkDown(f"the link to {self._where()} is down")
        self._send(frame)

    def send_config(self, config: Config, timeout_s: float) -> ConfigAck:
        """Send CONFIG and wait for its CONFIG_ACK (any thread). Raises LinkDown,
        ConfigRejected or TimeoutError."""
        deadline = time.monotonic() + timeout_s
        if not self._up.wait(timeout_s):
            raise LinkDown(f"the link to {self._where()} is down")
        future = self._submit(config)
        try:
            return future.result(timeout=max(0.0, deadline - time.monotonic()))
        except FutureTimeout as exc:
            raise TimeoutError(f"no CONFIG_ACK for config {config.config_id}") from exc

    # -- thread --------------------------------------------------------------

    def _where(self) -> str:
        return f"{self.endpoint[0]}:{self.endpoint[1]}"

    def _run(self) -> None:
        backoff = self._opt.backoff_initial_s
        while not self._stop.is_set():
            connects, began = self.stats.connects, time.monotonic()
            try:
                self._session()
            except (OSError, ProtocolError, LinkDown) as exc:
                self.stats.last_error = str(exc)
                if not self._stop.is_set():
                    log.warning("link to %s: %s", self._where(), exc)
            except Exception as exc:  # a bug must not end the reconnect loop
                self.stats.last_error = f"internal error: {exc}"
                log.exception("link to %s: internal error", self._where())
            finally:
                self._drop("link down")
            lasted = time.monotonic() - began
            if self.stats.connects != connects and lasted >= self._opt.backoff_max_s:
                # The link was up for a while (a flapping radio, not a peer that fails at once):
                # the first retry goes at once, the next ones back off.
                backoff = 0.0
            if self._stop.wait(backoff):
                break
            backoff = min(max(backoff * 2, self._opt.backoff_initial_s), self._opt.backoff_max_s)
        self.stats.state = "stopped"

    def _session(self) -> None:
        self.stats.state = "connecting"
        sock = socket.create_connection(self.endpoint, timeout=self._opt.connect_timeout_s)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self._sock = sock
        self.stats.state = "handshake"
        ok, splitter = client_handshake(sock, self._key)
        self._splitter = splitter
        self.stats.connects += 1
        self.stats.backpressure.reset(time.time_ns())
        log.info("link to %s authenticated (PubBroker config %d)", self._where(), ok.config_id)
        rtt = self._measure_rtt(sock, splitter)
        self.stats.state = "configuring"
        config = self._handler.on_connect(ok, rtt)
        if config is not None:
            self._submit(config, connecting=True)
        else:
            self.stats.state = "up"
        self._up.set()
        if self.on_up is not None:
            self.on_up()
        self._read_loop(sock, splitter)

    def _measure_rtt(self, sock: socket.socket, splitter: codec.FrameSplitter) -> float | None:
        """The median of ``ping_count`` PING round trips. Each PONG is awaited at most
        ``connect_timeout_s`` in all: DATA that keeps flowing (the PubBroker's running
        config) must not hold the connection here for ever; a missing PONG is skipped
        and the plan keeps the model's ping time."""
        rtts: list[float] = []
        for i in range(self._opt.ping_count):
            payload = struct.pack("<I", i) + os.urandom(4)
            start = time.monotonic()
            deadline = start + self._opt.connect_timeout_s
            self._send(codec.encode(Ping(payload)))
            while True:
                left = deadline - time.monotonic()
                if left <= 0:
                    log.warning("link to %s: no PONG in %g s; planning without this round trip",
                                self._where(), self._opt.connect_timeout_s)
                    break
                sock.settimeout(left)
                try:
                    frame = self._next_frame(sock, splitter)
                except TimeoutError:
                    continue
                if codec.is_data_type(frame.type):
                    self._on_data(frame)  # the running config, when resuming
                    continue
                if bf.is_backfill_type(frame.type):
                    self._on_backfill(frame)
                    continue
                msg = codec.decode(frame)
                if isinstance(msg, Pong) and msg.payload == payload:
                    rtts.append(time.monotonic() - start)
                    break
                self._handle(msg)
        if rtts:
            self.stats.rtt_s = statistics.median(rtts)
        return self.stats.rtt_s

    def _next_frame(self, sock: socket.socket, splitter: codec.FrameSplitter) -> codec.RawFrame:
        while True:
            frame = splitter.pop()
            if frame is not None:
                self.stats.frames_in += 1
                return frame
            data = sock.recv(65536)
            if not data:
                raise LinkDown("the PubBroker closed the link")
            self.stats.bytes_in += len(data)
            splitter.buf += data

    def _read_loop(self, sock: socket.socket, splitter: codec.FrameSplitter) -> None:
        last = time.monotonic()
        pinged = False
        self._round_trips.restart(last)
        while not self._stop.is_set():
            payload = self._round_trips.due(time.monotonic())
            if payload is not None:
                self._send(codec.encode(Ping(payload)))
            timeout = self._liveness_s()
            sock.settimeout(max(0.05, min(0.5, timeout / 4)))
            try:
                frame = self._next_frame(sock, splitter)
            except TimeoutError:
                silent = time.monotonic() - last
                if silent > timeout:
                    raise LinkDown(f"no frame for {silent:.1f} s") from None
                if silent > timeout / 2 and not pinged:
                    self._send(codec.encode(Ping(b"alive")))
                    pinged = True
                self._expire_pending()
                continue
            last, pinged = time.monotonic(), False
            if codec.is_data_type(frame.type):
                self._on_data(frame)
            elif bf.is_backfill_type(frame.type):
                self._on_backfill(frame)
            else:
                self._handle(codec.decode(frame))
            if self._pending:
                self._expire_pending()

    def _on_data(self, frame: codec.RawFrame) -> None:
        try:
            windows = self.receiver.on_frame(frame)
        except ProtocolError as exc:
            # DATA of a config this process never sent (the PubBroker still runs
            # the previous SubBroker's until our CONFIG applies), or out of
            # sequence: skipped until the next sync frame, never fatal.
            self.stats.bad_frames += 1
            if self.stats.bad_frames % 100 == 1:
                log.info("DATA skipped (%d so far): %s", self.stats.bad_frames, exc)
            return
        self.stats.data_frames += 1
        self.stats.last_data_ns = time.time_ns()
        if windows:
            self._handler.on_windows(windows)
            splitter = self._splitter
            waiting = len(splitter.buf) if splitter is not None else 0
            self.stats.backpressure.observe(windows[0].end_ns,
                                            waiting + socket_backlog(self._sock), time.time_ns())

    def _on_backfill(self, frame: codec.RawFrame) -> None:
        sink = self.backfill_sink
        if sink is not None:
            sink(frame)

    def _handle(self, msg: object) -> None:
        if isinstance(msg, ConfigAck):
            self._on_ack(msg)
        elif isinstance(msg, Status):
            self.stats.pubbroker = msg.as_dict()
            self._handler.on_status(msg)
        elif isinstance(msg, Ping):
            self._send(codec.encode(Pong(msg.payload)))
        elif isinstance(msg, ErrorMsg):
            log.error("PubBroker error %d: %s", msg.code, msg.message)
            self.stats.last_error = f"PubBroker error {msg.code}: {msg.message}"
            for cid in list(self._pending):
                self._fail(cid, ConfigRejected(msg.code, msg.message))
        elif isinstance(msg, Pong):
            rtt = self._round_trips.on_pong(msg.payload, time.monotonic())
            if rtt is not None:
                self.stats.rtt_s = rtt
        else:
            what = type(msg).__name__
            raise ProtocolError(ErrorCode.BAD_FRAME, f"unexpected {what} on an established link")

    def _on_ack(self, ack: ConfigAck) -> None:
        pending = self._pending.pop(ack.config_id, None)
        if pending is None:
            log.warning("CONFIG_ACK for config %d that was not sent", ack.config_id)
            return
        config, future = pending.config, pending.future
        if ack.status != 0:
            future.set_exception(ConfigRejected(ack.status, f"PubBroker refused config "
                                                f"{ack.config_id} (status {ack.status})"))
            return
        self.receiver.add_config(config, ack.epoch_ns)
        self._handler.on_config_acked(config, ack)
        self.stats.state = "up"
        future.set_result(ack)

    def _submit(self, config: Config, connecting: bool = False) -> Future[ConfigAck]:
        future: Future[ConfigAck] = Future()
        deadline = time.monotonic() + self._opt.ack_timeout_s
        self._pending[config.config_id] = _Pending(config, future, deadline, connecting)
        self._send(codec.encode(config))
        return future

    def _expire_pending(self) -> None:
        now = time.monotonic()
        for cid, pending in list(self._pending.items()):
            if now > pending.deadline:
                self._fail(cid, TimeoutError(f"no CONFIG_ACK for config {cid}"))
                if pending.connecting:
                    raise LinkDown(f"no CONFIG_ACK for config {cid}")

    def _fail(self, cid: int, exc: BaseException) -> None:
        pending = self._pending.pop(cid, None)
        if pending is not None and not pending.future.done():
            pending.future.set_exception(exc)

    def _send(self, data: bytes) -> None:
        sock = self._sock
        if sock is None:
            raise LinkDown("the link is down")
        with self._send_lock:
            sock.sendall(data)
        self.stats.bytes_out += len(data)

    def _drop(self, reason: str) -> None:
        self._up.clear()
        if self.stats.state != "stopped":
            self.stats.state = "down"
        for cid in list(self._pending):
            self._fail(cid, LinkDown(reason))
        sock, self._sock = self._sock, None
        if sock is not None:
            with contextlib.suppress(OSError):
                sock.shutdown(socket.SHUT_RDWR)
            sock.close()
