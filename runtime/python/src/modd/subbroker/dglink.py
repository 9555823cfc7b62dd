"""The link client over datagrams (udp, serial): the base station's side of
docs/protocol.md, "Datagram transports", on its own thread, with the same
interface as :class:`~modd.subbroker.link.LinkClient` (the TCP one).

The handshake travels in 0x41 datagrams and is retried (HELLO, then AUTH,
every second, at most 10 times each); the session key comes from its nonces.
CONFIG, PING, NACK go in tagged CONTROL datagrams (CONFIG resent every second
until its ack). DATA datagrams are verified before anything is decoded
(:class:`~modd.link.dgreceiver.DatagramReceiver`: forged, replayed, malformed
are dropped and counted), gaps are NACKed every accepted delay (at most 5
times a gap), and nothing else flows back but a PING every keepalive period.

Silence (no datagram for the liveness time) gets a PING; three times that
starts a new handshake, which resumes the running config when the PubBroker
still runs it, so that the slots lost during an outage are still asked for
(the PubBroker tags its ring again under the new session's key).
"""

from __future__ import annotations

import logging
import os
import struct
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future
from concurrent.futures import TimeoutError as FutureTimeout
from dataclasses import dataclass, field
from typing import Any

from modd_plan.linkbudget import datagram_capacity
from modd_plan.schedule import Schedule

from modd.link import backfill as bf
from modd.link import codec
from modd.link.auth import client_proof, server_proof
from modd.link.datagram import (
    BASE_TO_DRONE,
    DGRAM_CONTROL,
    DGRAM_CONTROL_FRAGMENT,
    DGRAM_DATA,
    DGRAM_DATA_BITMAP,
    DGRAM_FRAGMENT,
    DGRAM_HANDSHAKE,
    DRONE_TO_BASE,
    MAX_FRAGMENTS,
    ControlPieces,
    Forged,
    ReplayWindow,
    encode_control,
    encode_control_fragments,
    encode_handshake,
    encode_nack,
    session_key,
    verify_control,
    verify_control_fragment,
)
from modd.link.dgreceiver import DatagramReceiver
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
    Ping,
    Pong,
    ProtocolError,
    Status,
)
from modd.link.receiver import Window
from modd.link.schedule import SlotIterator

from .config import LinkOptions
from .dgport import DatagramPort
from .link import ConfigRejected, LinkDown, LinkHandler, LinkStats, RoundTrips

log = logging.getLogger("modd.subbroker.dglink")

RETRY_S = 1.0  # handshake and CONFIG resent this often ...
RETRIES = 10  # ... at most this many times
KEEPALIVE_S = 30.0
MAX_NACK_ASKS = 5
PUBBROKER_COUNTS = ("datagrams_sent", "datagrams_resent", "nacks", "slots_dropped", "forged",
                    "replayed")
OVERDUE_GRACE_S = 0.25  # beyond the learnt lateness, before an overdue datagram is asked for


@dataclass
class RadioCounters:
    """What the status reports of a datagram link (docs/subbroker.md, "Status")."""

    datagrams_in: int = 0
    forged: int = 0
    replayed: int = 0
    malformed: int = 0
    unknown_config: int = 0
    nacks: int = 0
    handshakes: int = 0
    _rates: deque[tuple[float, int, int]] = field(default_factory=deque)


@dataclass
class _Run:
    config: Config
    epoch_ns: int
    receiver: DatagramReceiver
    schedule: Schedule
    # Smallest (arrival - date of a datagram's last slot), s: the link's latency plus the
    # clocks' offset, learnt from the traffic, so that a lost datagram is asked for when
    # it is overdue rather than when the next one arrives (docs/protocol.md, "NACK").
    lateness: float | None = None
    asked_slot: int = -1
    asked_at: float = float("-inf")
    asks: int = 0
    recovered: int = 0  # slots that came after an overdue NACK (no gap opened)
    # The epoch of the config that replaced this one: its slots dated before it still
    # come (the PubBroker's group packed before the switch), none after.
    end_ns: int | None = None


@dataclass
class _Pending:
    config: Config
    future: Future[ConfigAck]
    deadline: float
    connecting: bool
    sent: float = 0.0
    tries: int = 0


def control_frames(payload: bytes) -> list[codec.RawFrame] | None:
    """The link frames of a control datagram, in order, or None when the payload is not
    whole frames. Usually one; the PubBroker puts a backfill's PROGRESS in the same
    datagram as the DATA or END it reports on (docs/protocol.md, "Datagram types"): an END
    read past would leave its backfill running for ever.

    >>> [f.type for f in control_frames(bytes([1, 0x06, 2, 0x07, 0]))]
    [6, 7]
    """
    out: list[codec.RawFrame] = []
    rest = payload
    try:
        while rest:
            f = codec.split_frame(rest)
            if f is None:
                return None
            out.append(f)
            rest = rest[f.size:]
    except ProtocolError:
        return None
    return out or None


class DatagramLinkClient:
    """Keeps one authenticated datagram session with the PubBroker."""

    def __init__(self, open_port: Callable[[], DatagramPort], where: str, transport: str,
                 key: bytes, options: LinkOptions, handler: LinkHandler,
                 delay_s: float = 1.0, liveness_s: Callable[[], float] = lambda: 3.0,
                 max_packet: int | None = None) -> None:
        self.transport = transport
        #: the radio's largest packet (the model's link.maxPacket): a control message
        #: larger than one packet goes as control fragments (at most 16); a CONFIG that
        #: needs more is refused here, with its sizes
        self._max_packet = max_packet
        self._open_port = open_port
        self._where = where
        self._psk = key
        self._opt = options
        self._handler = handler
        #: the accepted delay the PubBroker packs with: the configured one until a
        #: CONFIG carrying another is acked (docs/protocol.md, "CONFIG")
        self.delay_s = delay_s
        self._configured_delay_s = delay_s
        self._liveness_s = liveness_s
        self.stats = LinkStats()
        self.radio = RadioCounters()
        self._port: DatagramPort | None = None
        self._key = b""
        self._old_key = b""
        self._counter = 0
        self._window = ReplayWindow(64)
        self._pieces = ControlPieces()
        self._runs: dict[int, _Run] = {}
        self._pending: dict[int, _Pending] = {}
        self._pings: dict[bytes, float] = {}
        self._round_trips = RoundTrips(options.ping_period_s)
        self._rtt = 0.0
        self._last_sent = 0.0
        self._lock = threading.Lock()
        self._up = threading.Event()
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="modd-dglink", daemon=True)
        #: Backfill frames from the PubBroker (control datagrams) go here; ``on_up`` runs
        #: after each (re)connection, as on the TCP link (subbroker/link.py).
        self.backfill_sink: Callable[[codec.RawFrame], None] | None = None
        self.on_up: Callable[[], None] | None = None

    # -- public (as LinkClient) ----------------------------------------------------

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=5.0)
        self._close()

    @property
    def up(self) -> bool:
        return self._up.is_set()

    def send_config(self, config: Config, timeout_s: float) -> ConfigAck:
        deadline = time.monotonic() + timeout_s
        if not self._up.wait(timeout_s):
            raise LinkDown(f"the link to {self._where} is down")
        future = self._submit(config)
        try:
            return future.result(timeout=max(0.0, deadline - time.monotonic()))
        except FutureTimeout as exc:
            raise TimeoutError(f"no CONFIG_ACK for config {config.config_id}") from exc

    def send_frame(self, frame: bytes) -> None:
        """Send one encoded frame (a backfill request or cancel) as a control
        datagram; raises LinkDown."""
        if not self._up.is_set():
            raise LinkDown("the link is down")
        self._control(frame)

    def radio_status(self) -> dict[str, Any]:
        """Loss, retransmissions, forged/dropped datagrams, measured bytes/s on the
        wire per direction (headers or framing included), over the last 10 s."""
        r = self.radio
        rx = [run.receiver for run in self._runs.values()]
        received = sum(x.stats.slots for x in rx)
        recovered = (sum(x.gaps.recovered for x in rx)
                     + sum(run.recovered for run in self._runs.values()))
        lost = sum(x.gaps.lost for x in rx)
        missing = sum(x.gaps.missing for x in rx)
        seen = received + lost + missing
        rates = list(r._rates)
        down = up = None
        if len(rates) >= 2 and rates[-1][0] > rates[0][0]:
            span = rates[-1][0] - rates[0][0]
            down = round((rates[-1][1] - rates[0][1]) / span, 1)
            up = round((rates[-1][2] - rates[0][2]) / span, 1)
        port = self._port
        return {
            "transport": self.transport,
            "accepted_delay_s": self.delay_s,
            "wire_bytes_in_per_s": down,
            "wire_bytes_out_per_s": up,
            "loss": round((recovered + lost + missing) / seen, 4) if seen else 0.0,
            "slots_received": received,
            "retransmissions": recovered,
            "slots_lost": lost,
            "slots_missing": missing,
            "nacks": r.nacks,
            "datagrams_in": r.datagrams_in,
            "forged": r.forged,
            "replayed": r.replayed,
            "malformed": r.malformed + (port.corrupt if port is not None else 0),
            "unknown_config": r.unknown_config,
            "handshakes": r.handshakes,
            "pubbroker": self._pubbroker_counts(),
        }

    def _pubbroker_counts(self) -> dict[str, int] | None:
        """The PubBroker's side from its last STATUS (docs/protocol.md, STATUS 24..29):
        datagrams sent, resent, NACKs it got, slots it dropped, forged and replayed
        datagrams it refused; None before its first STATUS (or from an older broker)."""
        st = self.stats.pubbroker
        if not st or "link_datagrams_sent" not in st:
            return None
        return {name: int(st[f"link_{name}"]) for name in PUBBROKER_COUNTS}

    # -- thread --------------------------------------------------------------------

    def _run(self) -> None:
        backoff = self._opt.backoff_initial_s
        while not self._stop.is_set():
            try:
                self._session()
                backoff = self._opt.backoff_initial_s
            except (OSError, ProtocolError, LinkDown, ConnectionError) as exc:
                self.stats.last_error = str(exc)
                if not self._stop.is_set():
                    log.warning("link to %s: %s", self._where, exc)
            except Exception as exc:  # a bug must not end the reconnect loop
                self.stats.last_error = f"internal error: {exc}"
                log.exception("link to %s: internal error", self._where)
            finally:
                self._drop("link down")
            if self._stop.wait(backoff):
                break
            backoff = min(max(backoff * 2, self._opt.backoff_initial_s), self._opt.backoff_max_s)
        self.stats.state = "stopped"

    def _session(self) -> None:
        if self._port is None:
            self._port = self._open_port()
        self.stats.state = "handshake"
        ok = self._handshake()
        self.stats.connects += 1
        self.radio.handshakes += 1
        self.stats.backpressure.reset(time.time_ns())
        log.info("link to %s authenticated over %s (PubBroker config %d)", self._where,
                 self.transport, ok.config_id)
        self._measure_rtt()
        self.stats.state = "configuring"
        config = self._handler.on_connect(ok, self.stats.rtt_s)
        if config is not None:
            self._submit(config, connecting=True)
        else:
            self.stats.state = "up"
        self._up.set()
        if self.on_up is not None:
            self.on_up()
        self._loop()

    def _handshake(self) -> AuthOk:
        nonce = os.urandom(16)
        challenge = self._exchange(codec.encode(Hello(VERSION, nonce)), Challenge, "HELLO")
        assert isinstance(challenge, Challenge)
        auth = codec.encode(Auth(client_proof(self._psk, nonce, challenge.nonce)))
        ok = self._exchange(auth, AuthOk, "AUTH")
        assert isinstance(ok, AuthOk)
        if ok.mac != server_proof(self._psk, nonce, challenge.nonce):
            raise ProtocolError(ErrorCode.AUTH_FAILED, "the broker does not know the key")
        self._old_key, self._key = self._key, session_key(self._psk, nonce, challenge.nonce)
        self._window = ReplayWindow(64)
        self._pieces = ControlPieces()
        for run in self._runs.values():
            run.receiver.key = self._key
        return ok

    def _exchange(self, frame: bytes, want: type, what: str) -> object:
        """Send a handshake frame every RETRY_S until the answer comes."""
        for _ in range(RETRIES):
            self._send(encode_handshake(frame))
            deadline = time.monotonic() + RETRY_S
            while (left := deadline - time.monotonic()) > 0:
                if self._stop.is_set():
                    raise LinkDown("stopping")
                for raw in self._recv(left):
                    if not raw or raw[0] != DGRAM_HANDSHAKE:
                        self._on_datagram(raw)  # DATA of the running session, while it lasts
                        continue
                    f = codec.split_frame(raw[1:])
                    if f is None:
                        continue
                    msg = codec.decode(f)
                    if isinstance(msg, ErrorMsg):
                        raise ProtocolError(ErrorCode(msg.code),
                                            f"broker refused {what}: {msg.message}")
                    if isinstance(msg, want):
                        return msg
        raise LinkDown(f"no answer to {what} after {RETRIES} tries")

    def _measure_rtt(self) -> None:
        rtts: list[float] = []
        for i in range(self._opt.ping_count):
            payload = struct.pack("<I", i) + os.urandom(4)
            start = time.monotonic()
            self._pings[payload] = start
            self._control(codec.encode(Ping(payload)))
            deadline = start + RETRY_S
            while payload in self._pings and time.monotonic() < deadline:
                for raw in self._recv(deadline - time.monotonic()):
                    self._on_datagram(raw)
            if payload not in self._pings:
                rtts.append(self._rtt)
            self._pings.pop(payload, None)
        if rtts:
            self.stats.rtt_s = sorted(rtts)[len(rtts) // 2]

    def _loop(self) -> None:
        last = time.monotonic()
        pinged = 0.0
        self._round_trips.restart(last)
        while not self._stop.is_set():
            got = self._recv(0.05)
            now = time.monotonic()
            payload = self._round_trips.due(now)
            if payload is not None:
                self._control(codec.encode(Ping(payload)))
            for raw in got:
                if self._on_datagram(raw):
                    last = now
            self._sample_rates(now)
            for run in self._runs.values():
                # the gaps' ranges go under this session's one control counter (the
                # receiver's own NACK datagrams would reuse its numbers: dropped as replays)
                ranges = run.receiver.gaps.due(now, self._ask_every())
                if ranges:
                    self.radio.nacks += 1
                    self._control(encode_nack(ranges))
                self._ask_overdue(run, now)
            self._resend_pending(now)
            silence = self._silence_s()
            silent = now - last
            if silent > 3 * silence:
                raise LinkDown(f"nothing from the PubBroker for {silent:.1f} s")
            if (silent > silence and now - pinged > silence) or now - self._last_sent > KEEPALIVE_S:
                self._control(codec.encode(Ping(b"alive")))
                pinged = now

    def _ask_every(self) -> float:
        """How long an ask waits for its answer before it is repeated: twice the
        RTT and a margin, at most the accepted delay (a lost NACK or resend costs
        a round trip, not a whole accepted delay)."""
        rtt = self.stats.rtt_s if self.stats.rtt_s is not None else 0.2
        return min(self.delay_s, max(0.3, 2 * rtt + 0.15))

    def _ask_overdue(self, run: _Run, now: float) -> None:
        """NACK the next expected slot once the datagram holding it is overdue
        (sent at the latest its date + the accepted delay, arriving the learnt
        lateness after): a lost datagram is asked for at once, not when the next
        one shows the gap. Every accepted delay, at most MAX_NACK_ASKS times."""
        nxt = run.receiver.gaps.next
        if run.lateness is None or nxt < 0:
            return
        date_ns = run.epoch_ns + run.schedule.slot_date_us(nxt) * 1000
        if run.end_ns is not None and date_ns >= run.end_ns:
            return  # a replaced config: no slot of it after the switch
        if nxt != run.asked_slot:
            run.asked_slot, run.asks, run.asked_at = nxt, 0, float("-inf")
        if run.asks >= MAX_NACK_ASKS or now - run.asked_at < self._ask_every():
            return
        due = (run.epoch_ns / 1e9 + run.schedule.slot_date_us(nxt) / 1e6 + self.delay_s
               + run.lateness + OVERDUE_GRACE_S)
        if time.time() < due:
            return
        run.asks += 1
        run.asked_at = now
        self.radio.nacks += 1
        self._control(encode_nack([(nxt, 1)]))

    def _silence_s(self) -> float:
        return max(self._liveness_s(), 2 * self.delay_s + 1.0)

    def _sample_rates(self, now: float) -> None:
        port = self._port
        if port is None:
            return
        rates = self.radio._rates
        if not rates or now - rates[-1][0] >= 0.25:
            rates.append((now, port.wire_in, port.wire_out))
        while rates and rates[0][0] < now - 10.0:
            rates.popleft()

    # -- receiving -----------------------------------------------------------------

    def _recv(self, timeout_s: float) -> list[bytes]:
        port = self._port
        if port is None:
            raise LinkDown("the link is down")
        got = port.recv(max(0.0, timeout_s))
        self.stats.bytes_in += sum(len(d) for d in got)
        self.radio.datagrams_in += len(got)
        return got

    def _on_datagram(self, raw: bytes) -> bool:
        """Handle one datagram; True when it verified (the PubBroker is there)."""
        if not raw:
            return False
        kind = raw[0]
        if kind in (DGRAM_DATA, DGRAM_DATA_BITMAP, DGRAM_FRAGMENT) and len(raw) > 1:
            return self._on_data(raw)
        if kind == DGRAM_CONTROL and self._key:
            try:
                counter, frame = verify_control(raw, self._key, DRONE_TO_BASE)
            except Forged:
                self.radio.forged += 1
                return False
            except ProtocolError:
                self.radio.malformed += 1
                return False
            if not self._window.accept(counter):
                self.radio.replayed += 1
                return False
            return self._on_control_frames(frame)
        if kind == DGRAM_CONTROL_FRAGMENT and self._key:
            try:
                piece = verify_control_fragment(raw, self._key, DRONE_TO_BASE)
            except Forged:
                self.radio.forged += 1
                return False
            except ProtocolError:
                self.radio.malformed += 1
                return False
            if not self._window.accept(piece.counter):
                self.radio.replayed += 1
                return False
            before = self._pieces.malformed
            whole = self._pieces.add(piece)
            self.radio.malformed += self._pieces.malformed - before
            return self._on_control_frames(whole) if whole is not None else True
        self.radio.malformed += 1
        return False

    def _on_control_frames(self, frame: bytes) -> bool:
        """The link frames of a control message (one datagram's, or put back
        together from its fragments), handled in order."""
        frames = control_frames(frame)
        if frames is None:
            self.radio.malformed += 1
            return False
        self.stats.frames_in += len(frames)
        for f in frames:
            if bf.is_backfill_type(f.type):
                sink = self.backfill_sink
                if sink is not None:
                    sink(f)
            else:
                self._handle(codec.decode(f))
        return True

    def _on_data(self, raw: bytes) -> bool:
        run = self._runs.get(raw[1])
        if run is None:
            self.radio.unknown_config += 1
            return False
        rx = run.receiver
        before = (rx.stats.forged, rx.stats.replayed, rx.stats.malformed)
        slots = rx.on_datagram(raw, time.monotonic())
        if not slots and rx.stats.forged > before[0] and self._old_key:
            rx.key, rx.stats.forged = self._old_key, rx.stats.forged - 1  # the last session's
            slots = rx.on_datagram(raw, time.monotonic())
            rx.key = self._key
        after = (rx.stats.forged, rx.stats.replayed, rx.stats.malformed)
        self.radio.forged += after[0] - before[0]
        self.radio.replayed += after[1] - before[1]
        self.radio.malformed += after[2] - before[2]
        if not slots:
            return False
        if run.asks and slots[0][0] <= run.asked_slot < slots[0][0] + len(slots):
            run.recovered += len(slots)  # the answer to an overdue NACK
        last = run.epoch_ns / 1e9 + run.schedule.slot_date_us(slots[-1][0]) / 1e6
        late = time.time() - last
        run.lateness = late if run.lateness is None else min(run.lateness, late)
        self.stats.data_frames += 1
        self.stats.frames_in += 1
        self.stats.last_data_ns = time.time_ns()
        for windows in self._windows(run, slots):  # one slot at a time, as over tcp
            self._handler.on_windows(windows)
            self.stats.backpressure.observe(windows[0].end_ns, 0, time.time_ns())
        return True

    @staticmethod
    def _windows(run: _Run, slots: list[tuple[int, list[Any]]]) -> list[list[Window]]:
        """The windows of each slot that has a value (an empty slot, which tcp
        does not send, delivers nothing)."""
        it = SlotIterator([s.period_us for s in run.config.streams])
        it.skip_to(slots[0][0])
        out: list[list[Window]] = []
        for index, values in slots:
            it.skip_to(index)
            slot = next(it)
            if not any(v.present for v in values):
                continue
            end = run.epoch_ns + slot.offset_us * 1000
            out.append([Window(run.config.config_id, index, sid,
                               end - run.config.streams[sid].period_us * 1000, end, v)
                        for sid, v in zip(slot.streams, values, strict=True)])
        return out

    def _handle(self, msg: object) -> None:
        if isinstance(msg, ConfigAck):
            self._on_ack(msg)
        elif isinstance(msg, Pong):
            start = self._pings.pop(msg.payload, None)
            if start is not None:
                self._rtt = time.monotonic() - start
            rtt = self._round_trips.on_pong(msg.payload, time.monotonic())
            if rtt is not None:
                self.stats.rtt_s = rtt
        elif isinstance(msg, Status):
            self.stats.pubbroker = msg.as_dict()
            self._handler.on_status(msg)
        elif isinstance(msg, Ping):
            self._control(codec.encode(Pong(msg.payload)))
        elif isinstance(msg, ErrorMsg):
            log.error("PubBroker error %d: %s", msg.code, msg.message)
            self.stats.last_error = f"PubBroker error {msg.code}: {msg.message}"
            for cid in list(self._pending):
                self._fail(cid, ConfigRejected(msg.code, msg.message))

    def _on_ack(self, ack: ConfigAck) -> None:
        pending = self._pending.pop(ack.config_id, None)
        if pending is None:
            return  # the ack of a retry that crossed the first ack
        if ack.status != 0:
            pending.future.set_exception(ConfigRejected(
                ack.status, f"PubBroker refused config {ack.config_id} (status {ack.status})"))
            return
        config = pending.config
        self.delay_s = (self._configured_delay_s if config.accepted_delay_ms is None
                        else config.accepted_delay_ms / 1000)
        periods = [s.period_us for s in config.streams]
        receiver = DatagramReceiver(self._key, config.config_id, periods, config.kinds())
        receiver.gaps.max_asks = MAX_NACK_ASKS
        # the running config's last slots (up to the new epoch, packed before the switch,
        # up to the old accepted delay late) are still decoded: the previous run is kept
        # until the next config replaces it
        runs = {cid: run for cid, run in self._runs.items()
                if run.end_ns is None and cid != config.config_id}
        for run in runs.values():
            run.end_ns = ack.epoch_ns
        runs[config.config_id] = _Run(config, ack.epoch_ns, receiver,
                                      Schedule.from_periods_us(periods))
        self._runs = runs
        self._handler.on_config_acked(config, ack)
        self.stats.state = "up"
        pending.future.set_result(ack)

    # -- sending -------------------------------------------------------------------

    def _submit(self, config: Config, connecting: bool = False) -> Future[ConfigAck]:
        future: Future[ConfigAck] = Future()
        too_big = self._config_too_big(config)
        if too_big:
            log.error("%s: %s", self._where, too_big)
            future.set_exception(ConfigRejected(ErrorCode.BAD_CONFIG, too_big))
            return future
        deadline = time.monotonic() + self._opt.ack_timeout_s
        with self._lock:
            self._pending[config.config_id] = _Pending(config, future, deadline, connecting)
        self._resend_pending(time.monotonic())
        return future

    def _config_too_big(self, config: Config) -> str:
        """Why ``config`` cannot travel in the control fragments of this radio
        (at most 16 packets), or ""."""
        if self._max_packet is None:
            return ""
        fits = datagram_capacity(self.transport, self._max_packet)
        try:
            encode_control_fragments(1 << 32, codec.encode(config), fits, bytes(32),
                                     BASE_TO_DRONE)
        except ValueError as exc:
            size = len(codec.encode(config))
            return (f"config {config.config_id} is {size} B, more than the {MAX_FRAGMENTS} "
                    f"control fragments of this {self.transport} link carry ({fits} B datagrams "
                    f"of link.maxPacket {self._max_packet} B: {exc}); raise link.maxPacket if "
                    f"the radio allows it, or send fewer streams")
        return ""

    def _resend_pending(self, now: float) -> None:
        with self._lock:
            items = list(self._pending.items())
        for cid, p in items:
            if now > p.deadline or p.tries >= RETRIES:
                self._fail(cid, TimeoutError(f"no CONFIG_ACK for config {cid}"))
                if p.connecting:
                    raise LinkDown(f"no CONFIG_ACK for config {cid}")
                continue
            if now - p.sent >= RETRY_S:
                p.sent, p.tries = now, p.tries + 1
                self._control(codec.encode(p.config))

    def _fail(self, cid: int, exc: BaseException) -> None:
        with self._lock:
            pending = self._pending.pop(cid, None)
        if pending is not None and not pending.future.done():
            pending.future.set_exception(exc)

    def _control(self, frame: bytes) -> None:
        """One control message: a CONTROL datagram, or control fragments under
        consecutive counters when it is larger than one packet of the radio."""
        with self._lock:
            raw = encode_control(self._counter + 1, frame, self._key, BASE_TO_DRONE)
            fits = (datagram_capacity(self.transport, self._max_packet)
                    if self._max_packet is not None else None)
            if fits is None or len(raw) <= fits:
                self._counter += 1
                datagrams = [raw]
            else:
                datagrams = encode_control_fragments(self._counter + 1, frame, fits, self._key,
                                                     BASE_TO_DRONE)
                self._counter += len(datagrams)
        for d in datagrams:
            self._send(d)

    def _send(self, raw: bytes) -> None:
        port = self._port
        if port is None:
            raise LinkDown("the link is down")
        with self._lock:
            port.send(raw)
        self._last_sent = time.monotonic()
        self.stats.bytes_out += len(raw)

    def _drop(self, reason: str) -> None:
        self._up.clear()
        if self.stats.state != "stopped":
            self.stats.state = "down"
        for cid in list(self._pending):
            self._fail(cid, LinkDown(reason))
        if self.transport == "serial":
            self._close()  # opened again: the device may have gone and come back

    def _close(self) -> None:
        port, self._port = self._port, None
        if port is not None:
            port.close()
