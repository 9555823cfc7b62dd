"""The base station's side of a link session, without the socket: frames in,
bytes out (docs/protocol.md), as the PubBroker's ``broker/link_session.hpp``.

One :class:`LinkSession` lives as long as its link client and holds what every
transport shares: the handshake (HELLO, CHALLENGE, AUTH, AUTH_OK proved back),
the PING round trips measured on connect, the CONFIG handed over by the
SubBroker (:meth:`LinkHandler.on_connect`), the CONFIGs awaiting their ack,
STATUS, PING/PONG, ERROR, the backfill sink and ``on_up``. What differs per
transport lives in a subclass: how a frame travels (``stream_session.py``: one
byte stream; ``dgsession.py``: tagged datagrams) and when silence means the
link is gone. A pump (``pump.py``) feeds it what the socket reads, ticks it and
writes out what it emits; nothing here reads a socket or the real clock.

>>> s = StreamSession(b"key", LinkOptions(), handler, clock=FakeClock())  # doctest: +SKIP
>>> s.begin(); s.take()            # [HELLO]                            # doctest: +SKIP
>>> s.feed(challenge); s.take()    # [AUTH]                             # doctest: +SKIP
"""

from __future__ import annotations

import hmac
import logging
import os
import statistics
import struct
import threading
from abc import ABC, abstractmethod
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field

from modd.link import backfill as bf
from modd.link import codec, status_read
from modd.link.auth import client_proof, keyed_nonce, server_proof
from modd.link.frames import (
    VERSION,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    ErrorCode,
    ErrorMsg,
    Hello,
    MsgType,
    Onboard,
    OnboardAck,
    Ping,
    Pong,
    ProtocolError,
    Status,
)

from .config import LinkOptions
from .linkhooks import Adopted, Clock, ConfigRejected, LinkDown, LinkHandler, LinkStats, SystemClock
from .roundtrips import RoundTrips

log = logging.getLogger("modd.subbroker.link")


@dataclass
class Pending:
    """A CONFIG awaiting its CONFIG_ACK."""

    config: Config
    future: Future[ConfigAck]
    deadline: float
    connecting: bool  # sent on connect: no ack in time drops the link
    sent: float = 0.0
    tries: int = 0


@dataclass
class _Handshake:
    """The step of the handshake (or of the round trips measured after it) under way."""

    step: str  # "HELLO", "AUTH", "PING"
    frame: bytes  # what is sent, and sent again while unanswered
    nonce: bytes = b""  # ours (HELLO), or the payload of the PING awaited
    server_nonce: bytes = b""
    sent_at: float = 0.0
    tries: int = 0
    ok: AuthOk | None = None
    rtts: list[float] = field(default_factory=list)
    ping: int = 0


class LinkSession(ABC):
    """The lifecycle and control frames of one link client's sessions (see the module)."""

    #: How long a handshake step waits for its answer, and how many times it is sent.
    handshake_wait_s = 2.0
    handshake_tries = 1
    #: How long the PING of each round trip measured on connect is awaited.
    ping_wait_s = 2.0
    #: A CONFIG is sent again this often until acked (None: sent once), at most ``config_tries``.
    config_resend_s: float | None = None
    config_tries: int | None = None

    def __init__(
        self,
        key: bytes,
        options: LinkOptions,
        handler: LinkHandler,
        liveness_s: Callable[[], float] = lambda: 3.0,
        clock: Clock | None = None,
        where: str = "the PubBroker",
    ) -> None:
        self.where = where
        self._psk = key
        self._opt = options
        self.handler = handler
        self.liveness_s = liveness_s
        self.clock: Clock = clock or SystemClock()
        self.stats = LinkStats()
        self._lock = threading.Lock()
        self._out: list[bytes] = []
        self._pending: dict[int, Pending] = {}
        self._onboard: dict[int, Future[OnboardAck]] = {}  # ONBOARDs awaiting their ack
        self._round_trips = RoundTrips(options.ping_period_s)
        self._up = threading.Event()
        self._hs: _Handshake | None = None
        self._last_in = 0.0  # when the PubBroker was last heard
        self.answered_at = 0.0  # when it last answered a PING of this session (a PONG)
        #: Backfill frames from the PubBroker go here (link thread); ``on_up`` runs after each
        #: (re)connection, so that running backfills are asked for again with their resume point.
        self.backfill_sink: Callable[[codec.RawFrame], None] | None = None
        self.on_up: Callable[[], None] | None = None
        self._setup()

    # -- what a transport provides --------------------------------------------------

    def _setup(self) -> None:  # noqa: B027 (an optional hook: nothing by default)
        """The transport's own state (called at the end of ``__init__``)."""

    @abstractmethod
    def _wrap(self, frame: bytes) -> list[bytes]:
        """What carries one link frame of an established session."""

    def _wrap_handshake(self, frame: bytes) -> list[bytes]:
        return self._wrap(frame)

    def _over(self) -> str:
        """What the authentication log line says of the transport ("" over tcp; the
        datagram links name theirs, as the tests and operators read it)."""
        return ""

    def _authenticated(self, nonce: bytes, server_nonce: bytes) -> None:  # noqa: B027
        """The handshake proved the key both ways (a datagram session derives its key)."""

    @abstractmethod
    def _accept_config(self, config: Config, ack: ConfigAck) -> None:
        """A CONFIG the PubBroker acked: its DATA is decoded from now on."""

    def _joined_at(self, config_id: int, slot: int) -> None:  # noqa: B027
        """A config adopted while it runs, its last slot at the station that sent it
        (datagrams read slot numbers near it; a byte stream resynchronises on its own)."""

    @abstractmethod
    def _check_silence(self, now: float) -> None:
        """PING a silent PubBroker, raise LinkDown when it stays silent too long."""

    # -- the pump's side ---------------------------------------------------------------

    @property
    def up(self) -> bool:
        return self._up.is_set()

    def wait_up(self, timeout_s: float) -> bool:
        return self._up.wait(timeout_s)

    def take(self) -> list[bytes]:
        """What to write now, in order (each a stream chunk or one datagram)."""
        with self._lock:
            out, self._out = self._out, []
        self.stats.bytes_out += sum(len(d) for d in out)
        return out

    def begin(self) -> None:
        """A new connection: the handshake starts (HELLO)."""
        self.stats.state = "handshake"
        nonce = keyed_nonce(self._psk)  # the PubBroker tells it from a stranger's
        self._hs = _Handshake("HELLO", codec.encode(Hello(VERSION, nonce)), nonce)
        self._last_in = self.clock.monotonic()
        self._send_step(self._last_in)

    def close(self, reason: str) -> None:
        """The connection is gone: every CONFIG awaiting its ack fails with LinkDown."""
        self._up.clear()
        self._hs = None
        if self.stats.state != "stopped":
            self.stats.state = "down"
        for cid in list(self._pending):
            self._fail(cid, LinkDown(reason))
        with self._lock:
            self._out.clear()

    def tick(self) -> None:
        """Timers: handshake and PING retries, periodic PINGs, CONFIG resends and
        expiry, silence. Raises LinkDown (or ProtocolError) when the session is over."""
        now = self.clock.monotonic()
        if self._hs is not None:
            self._handshake_tick(now)
            return
        payload = self._round_trips.due(now)
        if payload is not None:
            self.send(codec.encode(Ping(payload)))
        self._expire_pending(now)
        self._check_silence(now)

    # -- any thread ----------------------------------------------------------------

    def send(self, frame: bytes) -> None:
        """Queue one encoded link frame (the pump writes it out)."""
        with self._lock:  # a datagram's counter is taken in the order of the queue
            self._out.extend(self._wrap(frame))

    def send_frame(self, frame: bytes) -> None:
        """Queue one encoded frame (a backfill request or cancel); raises LinkDown."""
        if not self._up.is_set():
            raise LinkDown("the link is down")
        self.send(frame)

    def submit(self, config: Config, connecting: bool = False) -> Future[ConfigAck]:
        """Send CONFIG; the future is its CONFIG_ACK (or ConfigRejected, TimeoutError,
        LinkDown)."""
        future: Future[ConfigAck] = Future()
        refused = self._refuse(config)
        if refused:
            future.set_exception(ConfigRejected(ErrorCode.BAD_CONFIG, refused))
            return future
        now = self.clock.monotonic()
        pending = Pending(config, future, now + self._opt.ack_timeout_s, connecting, now, 1)
        with self._lock:
            self._pending[config.config_id] = pending
        self.send(codec.encode(config))
        return future

    def submit_onboard(self, msg: Onboard) -> Future[OnboardAck]:
        """Send ONBOARD; the future is its ONBOARD_ACK (the caller waits with a
        timeout; ValueError when it cannot travel over this link)."""
        future: Future[OnboardAck] = Future()
        frame = codec.encode(msg)
        with self._lock:
            self._onboard[msg.config_id] = future
        try:
            self.send(frame)
        except ValueError as exc:  # more control fragments than a message may have
            with self._lock:
                self._onboard.pop(msg.config_id, None)
            future.set_exception(exc)
        return future

    def _on_onboard_ack(self, ack: OnboardAck) -> None:
        with self._lock:
            future = self._onboard.pop(ack.config_id, None)
        if future is None:
            log.debug("ONBOARD_ACK for config %d that is not awaited", ack.config_id)
        elif not future.done():
            future.set_result(ack)

    def _refuse(self, config: Config) -> str:
        """Why ``config`` cannot be sent over this transport, or ""."""
        return ""

    # -- handshake -------------------------------------------------------------------

    def _send_step(self, now: float) -> None:
        hs = self._hs
        assert hs is not None
        hs.sent_at, hs.tries = now, hs.tries + 1
        with self._lock:
            self._out.extend(
                self._wrap(hs.frame) if hs.step == "PING" else self._wrap_handshake(hs.frame)
            )

    def _handshake_tick(self, now: float) -> None:
        hs = self._hs
        assert hs is not None
        if hs.step == "PING":
            if now - hs.sent_at >= self.ping_wait_s:
                log.warning(
                    "link: no PONG in %g s; planning without this round trip", self.ping_wait_s
                )
                self._next_ping(now)
            return
        if now - hs.sent_at < self.handshake_wait_s:
            return
        if hs.tries >= self.handshake_tries:
            raise LinkDown(
                f"no answer to {hs.step} after {hs.tries} {'try' if hs.tries == 1 else 'tries'}"
            )
        self._send_step(now)

    @property
    def handshaking(self) -> bool:
        """HELLO or AUTH awaits its answer."""
        return self._hs is not None and self._hs.step != "PING"

    def on_handshake(self, msg: object, strict: bool) -> None:
        """A handshake frame (CHALLENGE, AUTH_OK or ERROR) while one is awaited; any other
        is a protocol error when ``strict`` (one byte stream), else ignored."""
        hs = self._hs
        if hs is None or hs.step == "PING":
            return
        if isinstance(msg, ErrorMsg):
            raise ProtocolError(ErrorCode(msg.code), f"broker refused {hs.step}: {msg.message}")
        if hs.step == "HELLO" and isinstance(msg, Challenge):
            proof = client_proof(self._psk, hs.nonce, msg.nonce)
            self._hs = _Handshake("AUTH", codec.encode(Auth(proof)), hs.nonce, msg.nonce)
            self._send_step(self.clock.monotonic())
        elif hs.step == "AUTH" and isinstance(msg, AuthOk):
            if not hmac.compare_digest(msg.mac, server_proof(self._psk, hs.nonce, hs.server_nonce)):
                raise ProtocolError(ErrorCode.AUTH_FAILED, "the broker does not know the key")
            self._authenticated(hs.nonce, hs.server_nonce)
            self.stats.connects += 1
            self.stats.backpressure.reset(self.clock.time_ns())
            log.info(
                "link to %s authenticated%s (PubBroker config %d)",
                self.where,
                self._over(),
                msg.config_id,
            )
            hs.ok, hs.step, hs.ping = msg, "PING", -1
            self._next_ping(self.clock.monotonic())
        elif strict:
            expected = "CHALLENGE" if hs.step == "HELLO" else "AUTH_OK"
            raise ProtocolError(
                ErrorCode.BAD_FRAME, f"expected {expected}, got {type(msg).__name__}"
            )

    def _next_ping(self, now: float) -> None:
        """The next of the ``ping_count`` round trips measured on connect, or the CONFIG
        once they are measured (a missing PONG is skipped: the plan keeps the model's)."""
        hs = self._hs
        assert hs is not None
        hs.ping += 1
        if hs.ping < self._opt.ping_count:
            hs.nonce = struct.pack("<I", hs.ping) + os.urandom(4)
            hs.frame = codec.encode(Ping(hs.nonce))
            hs.tries = 0
            self._send_step(now)
            return
        if hs.rtts:
            self.stats.rtt_s = statistics.median(hs.rtts)
        assert hs.ok is not None
        self._hs = None
        self._connected(hs.ok)

    def _connected(self, ok: AuthOk) -> None:
        self.stats.state = "configuring"
        config = self.handler.on_connect(ok, self.stats.rtt_s)
        if isinstance(config, Adopted):  # another station's, running: nothing to send
            self._accept_config(config.config, config.ack)
            self._joined_at(config.ack.config_id, config.slot)
            self.handler.on_config_acked(config.config, config.ack)
            self.stats.state = "up"
        elif config is not None:
            self.submit(config, connecting=True)
        else:
            self.stats.state = "up"
        now = self.clock.monotonic()
        self._last_in = now
        self._round_trips.restart(now)
        self._up.set()
        if self.on_up is not None:
            self.on_up()

    # -- frames in -------------------------------------------------------------------

    def heard(self) -> None:
        """The PubBroker was heard (a frame, a verified datagram)."""
        self._last_in = self.clock.monotonic()

    def on_frame(self, frame: codec.RawFrame, strict: bool = True) -> None:
        """One link frame that is not DATA (control, backfill)."""
        self.stats.frames_in += 1
        if bf.is_backfill_type(frame.type):
            sink = self.backfill_sink
            if sink is not None:
                sink(frame)
            return
        if frame.type == MsgType.STATUS:  # never a reason to drop the link: read what reads
            status, problems = status_read.read_status(frame.body)
            self._on_status(status, problems)
            return
        msg = codec.decode(frame)
        hs = self._hs
        if (
            isinstance(msg, Pong)
            and hs is not None
            and hs.step == "PING"
            and msg.payload == hs.nonce
        ):
            now = self.clock.monotonic()
            hs.rtts.append(now - hs.sent_at)
            self._next_ping(now)
        else:
            self._handle(msg, strict)

    def _on_status(self, msg: Status, problems: list[str]) -> None:
        """The PubBroker's counters and instruments, every field range-checked: a bad one
        is logged and left out (modd.link.status_read)."""
        counters, bad_counters = status_read.checked_counters(msg)
        sensors, bad_sensors = status_read.checked_sensors(msg.sensors)
        for p in problems + bad_counters + bad_sensors:
            log.warning("%s", p)
        self.stats.pubbroker = counters
        self.stats.sensors = sensors
        self.handler.on_status(msg)

    def _handle(self, msg: object, strict: bool) -> None:
        if isinstance(msg, ConfigAck):
            self._on_ack(msg)
        elif isinstance(msg, OnboardAck):
            self._on_onboard_ack(msg)
        elif isinstance(msg, Status):
            self._on_status(msg, [])
        elif isinstance(msg, Ping):
            self.send(codec.encode(Pong(msg.payload)))
        elif isinstance(msg, ErrorMsg):
            log.error("PubBroker error %d: %s", msg.code, msg.message)
            self.stats.last_error = f"PubBroker error {msg.code}: {msg.message}"
            for cid in list(self._pending):
                self._fail(cid, ConfigRejected(msg.code, msg.message))
        elif isinstance(msg, Pong):
            self.answered_at = self.clock.monotonic()
            rtt = self._round_trips.on_pong(msg.payload, self.clock.monotonic())
            if rtt is not None:
                self.stats.rtt_s = rtt
        elif strict:
            what = type(msg).__name__
            raise ProtocolError(ErrorCode.BAD_FRAME, f"unexpected {what} on an established link")

    def _on_ack(self, ack: ConfigAck) -> None:
        with self._lock:
            pending = self._pending.pop(ack.config_id, None)
        if pending is None:
            # over datagrams, the ack of a resend that crossed the first ack
            log.debug("CONFIG_ACK for config %d that is not awaited", ack.config_id)
            return
        if ack.status != 0:
            pending.future.set_exception(
                ConfigRejected(
                    ack.status, f"PubBroker refused config {ack.config_id} (status {ack.status})"
                )
            )
            return
        self._accept_config(pending.config, ack)
        self.handler.on_config_acked(pending.config, ack)
        self.stats.state = "up"
        pending.future.set_result(ack)

    # -- CONFIGs awaiting their ack --------------------------------------------------------

    def _expire_pending(self, now: float) -> None:
        with self._lock:
            items = list(self._pending.items())
        for cid, p in items:
            if now > p.deadline or (self.config_tries is not None and p.tries >= self.config_tries):
                self._fail(cid, TimeoutError(f"no CONFIG_ACK for config {cid}"))
                if p.connecting:
                    raise LinkDown(f"no CONFIG_ACK for config {cid}")
                continue
            if self.config_resend_s is not None and now - p.sent >= self.config_resend_s:
                p.sent, p.tries = now, p.tries + 1
                self.send(codec.encode(p.config))

    def _fail(self, cid: int, exc: BaseException) -> None:
        with self._lock:
            pending = self._pending.pop(cid, None)
        if pending is not None and not pending.future.done():
            pending.future.set_exception(exc)
