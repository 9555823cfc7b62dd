"""The link session over datagrams (udp, serial): docs/protocol.md,
"Datagram transports", without the port.

The handshake travels in 0x41 datagrams and is retried (HELLO, then AUTH,
every second, at most 10 times each); the session key comes from its nonces,
and the session is bound to the address its AUTH_OK came from (a datagram
from any other is dropped and counted). CONFIG, PING, NACK go in tagged
CONTROL datagrams (CONFIG resent every second until its ack). DATA datagrams
are verified before anything is decoded (:mod:`.dgruns`), gaps are NACKed,
and nothing else flows back but a PING every keepalive period.

Datagrams another station's modem heard (docs/fleet.md, "Diversity reception") come
through :meth:`DatagramSession.relayed`: from no address of this link, they are taken
on their tag alone; a copy this station had already (its own modem heard it too) is
dropped as a copy, not counted as a replay.

Silence (no datagram for the liveness time) gets a PING; three times that
ends the session, and the next handshake resumes the running config when the
PubBroker still runs it, so that the slots lost during an outage are still
asked for (the PubBroker tags its ring again under the new session's key).
"""

from __future__ import annotations

import logging
from collections import deque
from collections.abc import Callable, Hashable
from typing import Any, TypeVar

from modd_plan.linkbudget import datagram_capacity

from modd.link import codec
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
    session_key,
    verify_control,
    verify_control_fragment,
)
from modd.link.frames import Config, ConfigAck, Ping, ProtocolError
from modd.link.receiver import Window

from .config import LinkOptions
from .dgruns import PUBBROKER_COUNTS, RadioCounters, Runs, control_frames
from .linkhooks import Clock, LinkDown, LinkHandler
from .session import LinkSession

log = logging.getLogger("modd.subbroker.dglink")
_T = TypeVar("_T")

RETRY_S = 1.0  # handshake and CONFIG resent this often ...
RETRIES = 10  # ... at most this many times
KEEPALIVE_S = 30.0
FOREIGN_LOG_EVERY = 1000  # a datagram from another address is logged once per this many
FORWARDED_KEPT = 256  # datagrams other stations forwarded, kept to tell a copy from a replay


class DatagramSession(LinkSession):
    """A :class:`LinkSession` fed datagrams (see the module)."""

    handshake_wait_s = RETRY_S
    handshake_tries = RETRIES
    ping_wait_s = RETRY_S
    config_resend_s = RETRY_S
    config_tries = RETRIES

    def __init__(
        self,
        transport: str,
        key: bytes,
        options: LinkOptions,
        handler: LinkHandler,
        delay_s: float = 1.0,
        liveness_s: Callable[[], float] = lambda: 3.0,
        max_packet: int | None = None,
        clock: Clock | None = None,
        where: str = "the PubBroker",
        peer: Hashable | None = None,
    ) -> None:
        super().__init__(key, options, handler, liveness_s, clock, where)
        self.transport = transport
        #: the radio's largest packet (the model's link.maxPacket): a control message
        #: larger than one packet goes as control fragments (at most 16); a CONFIG that
        #: needs more is refused here, with its sizes
        self._max_packet = max_packet
        self.radio = RadioCounters()
        self.runs = Runs(delay_s, self.radio, self.clock)
        #: where datagrams may come from: the configured endpoint until a handshake
        #: binds the session to the address that proved the key (None: a serial line)
        self._expected = peer
        self._bound: Hashable | None = None
        self._source: Hashable | None = None
        self._key = b""
        self._counter = 0
        self._window = ReplayWindow(64)
        self._pieces = ControlPieces()
        self._pinged = 0.0
        self._last_sent = 0.0
        self._own_in = 0.0  # when this station's own modem last gave a verified datagram
        #: the last datagrams other stations forwarded: the same one from this station's
        #: own modem afterwards is a copy, not a replay
        self._forwarded: deque[bytes] = deque(maxlen=FORWARDED_KEPT)
        #: the handshake nonces of the running session (the fleet is told them: handover.py)
        self.nonces: tuple[bytes, bytes] | None = None

    @property
    def delay_s(self) -> float:
        """The accepted delay the PubBroker packs with (the configured one until a
        CONFIG carrying another is acked: docs/protocol.md, "CONFIG")."""
        return self.runs.delay_s

    # -- the session's framing ------------------------------------------------------

    def expect(self, peer: Hashable | None) -> None:
        """Datagrams come from ``peer`` (the port's: None for a serial line)."""
        self._expected = peer

    def begin(self) -> None:
        self._bound = None
        self._pinged = 0.0
        super().begin()
        self._own_in = self._last_in

    def _wrap_handshake(self, frame: bytes) -> list[bytes]:
        return [encode_handshake(frame)]

    def _wrap(self, frame: bytes) -> list[bytes]:
        """One control message: a CONTROL datagram, or control fragments under
        consecutive counters when it is larger than one packet of the radio
        (called under the session's lock: the counters go out in order)."""
        self._last_sent = self.clock.monotonic()
        raw = encode_control(self._counter + 1, frame, self._key, BASE_TO_DRONE)
        fits = self._fits()
        if fits is None or len(raw) <= fits:
            self._counter += 1
            return [raw]
        datagrams = encode_control_fragments(
            self._counter + 1, frame, fits, self._key, BASE_TO_DRONE
        )
        self._counter += len(datagrams)
        return datagrams

    def _fits(self) -> int | None:
        return (
            datagram_capacity(self.transport, self._max_packet)
            if self._max_packet is not None
            else None
        )

    def _over(self) -> str:
        return f" over {self.transport}"

    def _authenticated(self, nonce: bytes, server_nonce: bytes) -> None:
        self.runs.old_key, self._key = self._key, session_key(self._psk, nonce, server_nonce)
        self.nonces = (nonce, server_nonce)
        self._window = ReplayWindow(64)
        self._pieces = ControlPieces()
        self.runs.rekey(self._key)
        self._bound = self._source
        self.radio.handshakes += 1

    def _accept_config(self, config: Config, ack: ConfigAck) -> None:
        self.runs.accept(config, ack, self._key)

    def _joined_at(self, config_id: int, slot: int) -> None:
        self.runs.joined_at(config_id, slot)

    def _refuse(self, config: Config) -> str:
        """Why ``config`` cannot travel in the control fragments of this radio
        (at most 16 packets), or ""."""
        fits = self._fits()
        if fits is None:
            return ""
        try:
            encode_control_fragments(1 << 32, codec.encode(config), fits, bytes(32), BASE_TO_DRONE)
        except ValueError as exc:
            size = len(codec.encode(config))
            why = (
                f"config {config.config_id} is {size} B, more than the {MAX_FRAGMENTS} "
                f"control fragments of this {self.transport} link carry ({fits} B datagrams "
                f"of link.maxPacket {self._max_packet} B: {exc}); raise link.maxPacket if "
                f"the radio allows it, or send fewer streams"
            )
            log.error("%s: %s", self.where, why)
            return why
        return ""

    def read_heard(
        self,
        config: Config,
        epoch_ns: int,
        slot: int,
        nonces: tuple[bytes, bytes],
        datagrams: list[bytes],
    ) -> list[list[Window]]:
        """The windows, slot by slot, of DATA datagrams this station's modem heard while
        another station served (diversity.py), read under that station's session key
        (its ``nonces`` and the drone's link key), or under this session's own when they
        came before its config was taken, on ``config``'s grid near ``slot``. A
        decoder of its own: the session's gaps and NACKs are not touched. What does not
        verify (another session's, forged) is left out."""
        runs = Runs(self.delay_s, RadioCounters(), self.clock)
        ack = ConfigAck(config.config_id, 0, epoch_ns)
        runs.accept(config, ack, session_key(self._psk, *nonces))
        runs.old_key = self._key  # and this session's, before its config was taken
        runs.joined_at(config.config_id, slot)
        out: list[list[Window]] = []
        for raw in datagrams:
            if len(raw) > 1 and raw[0] in (DGRAM_DATA, DGRAM_DATA_BITMAP, DGRAM_FRAGMENT):
                out += runs.on_datagram(raw) or []
        return out

    # -- timers -------------------------------------------------------------------

    def tick(self) -> None:
        now = self.clock.monotonic()
        if self._hs is None:  # not before the round trips are measured
            for nack in self.runs.nacks(now, self._ask_every()):
                self.send(nack)
        super().tick()

    def _ask_every(self) -> float:
        """How long an ask waits for its answer before it is repeated: twice the
        RTT and a margin, at most the accepted delay (a lost NACK or resend costs
        a round trip, not a whole accepted delay)."""
        rtt = self.stats.rtt_s if self.stats.rtt_s is not None else 0.2
        return min(self.delay_s, max(0.3, 2 * rtt + 0.15))

    def _check_silence(self, now: float) -> None:
        """Silence ends the session; so does a drone that no longer answers this station
        while its datagrams come only through other stations' modems (this station's
        transmissions no longer reach it: another station should serve)."""
        silence = max(self.liveness_s(), 2 * self.delay_s + 1.0)
        silent = now - self._last_in
        if silent > 3 * silence:
            raise LinkDown(f"nothing from the PubBroker for {silent:.1f} s")
        unanswered = now - max(self._own_in, self.answered_at)
        if unanswered > 3 * silence:
            raise LinkDown(
                f"the PubBroker has not answered this station for {unanswered:.1f} s (its "
                "datagrams come only through other stations' modems)"
            )
        if (
            unanswered > silence and now - self._pinged > silence
        ) or now - self._last_sent > KEEPALIVE_S:
            self.send(codec.encode(Ping(b"alive")))
            self._pinged = now

    # -- datagrams in -------------------------------------------------------------

    def datagram(self, raw: bytes, source: Hashable | None = None) -> bool:
        """Handle one datagram from ``source``; True when it verified (the PubBroker
        is there). One from an address the session is not bound to is dropped."""
        self.stats.bytes_in += len(raw)
        self.radio.datagrams_in += 1
        allowed = self._bound if self._bound is not None else self._expected
        if allowed is not None and source != allowed:
            self.radio.foreign += 1
            if self.radio.foreign % FOREIGN_LOG_EVERY == 1:
                log.warning(
                    "link to %s: datagram from %s dropped, the session is bound to %s (%d so far)",
                    self.where,
                    source,
                    allowed,
                    self.radio.foreign,
                )
            return False
        self._source = source
        replayed = self.radio.replayed
        ok = self._on_datagram(raw)
        if ok:
            self.heard()
            self._own_in = self._last_in
        elif self.radio.replayed > replayed and raw in self._forwarded:
            self.radio.replayed = replayed  # another station forwarded it first
        return ok

    def relayed(self, raw: bytes) -> bool:
        """A datagram another station's modem heard: True when it verified under this
        session's key and brought something new. A handshake datagram is not taken (each
        station answers its own), nor anything before this session has its key."""
        if not self._key or not raw or raw[0] == DGRAM_HANDSHAKE:
            return False
        self.radio.heard_elsewhere += 1
        self.stats.bytes_in += len(raw)
        replayed = self.radio.replayed
        ok = self._on_datagram(raw)
        self.radio.replayed = replayed  # a copy of what this modem heard is no replay
        if ok:
            self.radio.heard_elsewhere_used += 1
            self._forwarded.append(raw)
            self.heard()
        return ok

    def _on_datagram(self, raw: bytes) -> bool:
        if not raw:
            return False
        kind = raw[0]
        if kind == DGRAM_HANDSHAKE:
            f = codec.split_frame(raw[1:])
            if f is not None and self.handshaking:
                self.on_handshake(codec.decode(f), strict=False)
            return False
        if kind in (DGRAM_DATA, DGRAM_DATA_BITMAP, DGRAM_FRAGMENT) and len(raw) > 1:
            return self._on_data(raw)
        if kind == DGRAM_CONTROL and self._key:
            return self._on_control(raw)
        if kind == DGRAM_CONTROL_FRAGMENT and self._key:
            return self._on_control_fragment(raw)
        self.radio.malformed += 1
        return False

    def _verified(self, verify: Callable[[bytes, bytes, bytes], _T], raw: bytes) -> _T | None:
        """``verify`` (a control datagram's or a control fragment's) under the session
        key; None, counted, when it is forged or malformed."""
        try:
            return verify(raw, self._key, DRONE_TO_BASE)
        except Forged:
            self.radio.forged += 1
        except ProtocolError:
            self.radio.malformed += 1
        return None

    def _fresh(self, counter: int) -> bool:
        if self._window.accept(counter):
            return True
        self.radio.replayed += 1
        return False

    def _on_control(self, raw: bytes) -> bool:
        verified = self._verified(verify_control, raw)
        if verified is None or not self._fresh(verified[0]):
            return False
        return self._on_control_frames(verified[1])

    def _on_control_fragment(self, raw: bytes) -> bool:
        piece = self._verified(verify_control_fragment, raw)
        if piece is None or not self._fresh(piece.counter):
            return False
        before = self._pieces.malformed
        whole = self._pieces.add(piece)
        self.radio.malformed += self._pieces.malformed - before
        return self._on_control_frames(whole) if whole is not None else True

    def _on_control_frames(self, frame: bytes) -> bool:
        """The link frames of a control message (one datagram's, or put back
        together from its fragments), handled in order."""
        frames = control_frames(frame)
        if frames is None:
            self.radio.malformed += 1
            return False
        for f in frames:
            self.on_frame(f, strict=False)
        return True

    def _on_data(self, raw: bytes) -> bool:
        deliveries = self.runs.on_datagram(raw)
        if deliveries is None:
            return False
        self.stats.data_frames += 1
        self.stats.frames_in += 1
        self.stats.last_data_ns = self.clock.time_ns()
        for windows in deliveries:  # one slot at a time, as over tcp
            self.handler.on_windows(windows)
            self.stats.backpressure.observe(windows[0].end_ns, 0, self.clock.time_ns())
        return True

    # -- status -------------------------------------------------------------------

    def sample_wire(self, wire_in: int, wire_out: int) -> None:
        """The port's wire counters (headers or framing included), for the rates."""
        self.runs.sample_wire(self.clock.monotonic(), wire_in, wire_out)

    def radio_status(self, corrupt: int = 0) -> dict[str, Any]:
        """Loss, retransmissions, forged/dropped datagrams, measured bytes/s on the
        wire per direction (headers or framing included), over the last 10 s;
        ``corrupt``: the frames the port's deframer refused."""
        return {
            "transport": self.transport,
            "accepted_delay_s": self.delay_s,
            **self.runs.status(self.radio, corrupt),
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
