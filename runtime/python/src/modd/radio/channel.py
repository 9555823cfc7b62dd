"""One direction of an emulated radio: decides, for each packet offered at a
time, whether it is dropped (and why) or when it arrives. Pure and seeded; the
clock is passed in, so tests drive it without sleeping.

>>> ch = Channel(RadioSpec(rate=1000, latency_ms=50), seed=1)
>>> ch.offer(b"x" * 100, now=0.0)  # 100 B at 1000 B/s, then 50 ms
0.15
"""

from __future__ import annotations

import math
import random
from collections import Counter
from dataclasses import dataclass, field, replace

# The largest UDP payload (IPv4, the link contract's): a larger ``packet`` means nothing.
from modd_contracts.link_wire_gen import MAX_PACKET as MAX_PACKET

#: Settings beyond these are mistakes (a radio that holds a packet for more than
#: ten minutes, or a queue of an hour, is not a radio any link could use).
MAX_LATENCY_MS = 600_000.0
MAX_QUEUE_S = 3600.0
SHARES = ("loss", "duplicate", "forge", "replay")


@dataclass(frozen=True)
class RadioSpec:
    """What the radio imposes (both directions alike)."""

    rate: float | None = None  # bytes/s, None: unlimited
    packet: int | None = None  # largest packet in bytes; larger ones are dropped
    loss: float = 0.0  # probability of losing a packet
    latency_ms: float = 0.0
    jitter_ms: float = 0.0  # uniform in [-jitter, +jitter], never before the send
    outages: tuple[tuple[float, float], ...] = ()  # (start s, duration s) from the start
    # Outages of the drone -> station direction only (the drone still hears the station:
    # a station whose receiver is blocked or swamped, its transmitter not)
    deaf: tuple[tuple[float, float], ...] = ()
    queue_s: float = 2.0  # a packet that would wait longer than this to be sent is dropped
    seed: int = 0
    duplicate: float = 0.0  # probability that a packet that passed arrives twice
    # An attacker on the air: a share of the packets that passed is followed by a
    # forged copy (one bit of the datagram flipped; over serial the frame's CRC is
    # made good again, so that the forgery reaches the tag check) ...
    forge: float = 0.0
    # ... or sent again REPLAY_AFTER_S later, as it was (a replay, not a duplicate).
    replay: float = 0.0

    def __post_init__(self) -> None:
        """Refuses settings no radio has, naming the setting and its range."""

        def bad(name: str, value: object, want: str) -> ValueError:
            return ValueError(f"radio setting {name}={value} is out of range: expected {want}")

        if self.rate is not None and not (math.isfinite(self.rate) and self.rate > 0):
            raise bad("rate", self.rate, "bytes/s > 0 (leave it out for no limit)")
        if self.packet is not None and not 1 <= self.packet <= MAX_PACKET:
            raise bad("packet", self.packet, f"a whole number of bytes in 1..{MAX_PACKET}")
        for name in SHARES:
            if not 0 <= getattr(self, name) <= 1:
                raise bad(name, getattr(self, name), "a share in 0..1")
        for name in ("latency_ms", "jitter_ms"):
            if not 0 <= getattr(self, name) <= MAX_LATENCY_MS:
                raise bad(name, getattr(self, name), f"ms in 0..{MAX_LATENCY_MS:.0f}")
        if not 0 < self.queue_s <= MAX_QUEUE_S:
            raise bad("queue_s", self.queue_s, f"seconds in (0, {MAX_QUEUE_S:.0f}]")
        if self.seed < 0:
            raise bad("seed", self.seed, "a whole number >= 0")
        for start, length in self.outages + self.deaf:
            if not (math.isfinite(start) and start >= 0 and math.isfinite(length) and length > 0):
                raise bad(
                    "outage", f"{start}+{length}", "start+duration in s, start >= 0, duration > 0"
                )

    @staticmethod
    def parse(text: str) -> RadioSpec:
        """``rate=3600,packet=252,loss=0.05,latency_ms=80,jitter_ms=20,outage=10+30,seed=7``
        (``deaf=10+30``: an outage of the drone -> station direction alone)
        (``duplicate=0.01``: a share of the packets arrives twice; ``forge=0.1``,
        ``replay=0.1``: an attacker forges or replays a share of them)
        (``outage`` may repeat: start+duration in seconds). Raises ValueError naming
        the bad item."""
        values: dict[str, float] = {}
        outages: list[tuple[float, float]] = []
        deaf: list[tuple[float, float]] = []
        for item in filter(None, (p.strip() for p in text.split(","))):
            key, sep, raw = item.partition("=")
            if not sep:
                raise ValueError(f"radio setting {item!r}: expected name=value")
            try:
                if key in ("outage", "deaf"):
                    start, _, length = raw.partition("+")
                    (outages if key == "outage" else deaf).append((float(start), float(length)))
                    continue
                value = float(raw)
            except ValueError:
                raise ValueError(f"radio setting {key!r}: {raw!r} is not a number") from None
            if key not in (
                "rate",
                "packet",
                "loss",
                "latency_ms",
                "jitter_ms",
                "queue_s",
                "seed",
                "duplicate",
                "forge",
                "replay",
            ):
                raise ValueError(
                    f"unknown radio setting {key!r}; expected rate, packet, loss, "
                    "latency_ms, jitter_ms, outage, deaf, queue_s, seed, duplicate, "
                    "forge or replay"
                )
            if key in values:
                raise ValueError(f"radio setting {key!r} given twice")
            if key in ("packet", "seed") and not (math.isfinite(value) and value.is_integer()):
                raise ValueError(f"radio setting {key}={raw}: expected a whole number")
            if not math.isfinite(value):
                raise ValueError(f"radio setting {key}={raw}: expected a finite number")
            values[key] = value
        return RadioSpec(
            rate=values.get("rate"),
            packet=int(values["packet"]) if "packet" in values else None,
            loss=values.get("loss", 0.0),
            latency_ms=values.get("latency_ms", 0.0),
            jitter_ms=values.get("jitter_ms", 0.0),
            outages=tuple(outages),
            deaf=tuple(deaf),
            queue_s=values.get("queue_s", 2.0),
            seed=int(values.get("seed", 0)),
            duplicate=values.get("duplicate", 0.0),
            forge=values.get("forge", 0.0),
            replay=values.get("replay", 0.0),
        )


@dataclass
class Channel:
    """One direction. ``offer`` returns the arrival time, or None when dropped
    (``dropped`` counts why: loss, outage, oversize, queue)."""

    spec: RadioSpec
    seed: int = 0
    start: float = 0.0
    passed: int = 0
    passed_bytes: int = 0
    dropped: Counter[str] = field(default_factory=Counter)
    duplicated: int = 0
    forged: int = 0
    replayed: int = 0
    _busy_until: float = 0.0
    _rng: random.Random = field(init=False)

    def __post_init__(self) -> None:
        self._rng = random.Random(self.seed)

    def hearing(self) -> Channel:
        """This channel as the drone -> station direction: its ``deaf`` outages too."""
        if self.spec.deaf:
            self.spec = replace(self.spec, outages=self.spec.outages + self.spec.deaf, deaf=())
        return self

    def in_outage(self, now: float) -> bool:
        t = now - self.start
        return any(s <= t < s + d for s, d in self.spec.outages)

    def offer(self, packet: bytes, now: float) -> float | None:
        s = self.spec
        if s.packet is not None and len(packet) > s.packet:
            self.dropped["oversize"] += 1
            return None
        if self.in_outage(now):
            self.dropped["outage"] += 1
            return None
        begin = max(now, self._busy_until)
        if begin - now > s.queue_s:
            self.dropped["queue"] += 1
            return None
        end = begin + (len(packet) / s.rate if s.rate else 0.0)
        self._busy_until = end  # a lost packet used the air time too
        if self._rng.random() < s.loss:
            self.dropped["loss"] += 1
            return None
        jitter = self._rng.uniform(-s.jitter_ms, s.jitter_ms) if s.jitter_ms else 0.0
        self.passed += 1
        self.passed_bytes += len(packet)
        return round(max(end, end + (s.latency_ms + jitter) / 1000), 9)

    def duplicates(self) -> bool:
        """Whether the packet that just passed arrives a second time."""
        if self.spec.duplicate and self._rng.random() < self.spec.duplicate:
            self.duplicated += 1
            return True
        return False

    def forgery(self, packet: bytes, serial: bool) -> bytes | None:
        """A forged copy of the packet that just passed (one bit flipped after the
        datagram's type byte), or None. Only datagrams with a tag (DATA, fragment,
        control) are forged: a handshake datagram carries its own proofs."""
        if not self.spec.forge or self._rng.random() >= self.spec.forge:
            return None
        from modd.link.serialframe import cobs_decode, encode_frame  # only when forging

        datagram = packet
        if serial:
            if not packet.endswith(b"\x00"):
                return None  # a piece of a frame: nothing an attacker could make verify
            try:
                datagram = cobs_decode(packet.rstrip(b"\x00"))[:-2]
            except ValueError:
                return None
        if len(datagram) < 6 or datagram[0] not in (0x30, 0x31, 0x32, 0x40):
            return None
        bad = bytearray(datagram)
        bad[self._rng.randrange(1, len(bad))] ^= 1 << self._rng.randrange(8)
        self.forged += 1
        return encode_frame(bytes(bad)) if serial else bytes(bad)

    def replays(self) -> bool:
        """Whether the packet that just passed is sent again later, as it was."""
        if self.spec.replay and self._rng.random() < self.spec.replay:
            self.replayed += 1
            return True
        return False

    def summary(self) -> str:
        drops = ", ".join(f"{k} {v}" for k, v in sorted(self.dropped.items())) or "none"
        lost = sum(self.dropped.values())
        dup = f", duplicated {self.duplicated}" if self.duplicated else ""
        dup += f", forged {self.forged}" if self.forged else ""
        dup += f", replayed {self.replayed}" if self.replayed else ""
        return f"passed {self.passed} ({self.passed_bytes} B), dropped {lost} ({drops}){dup}"
