"""The link budget per transport: bytes per second on the wire of the declared
link (tcp, udp or serial) with that transport's headers and framing, its
share of the radio's usable bytes/s, the delay each subscription sees, and
the subscriptions that make the plan exceed the budget.

Layouts (docs/protocol.md, "Datagram transports"), kept in step with the
codec in ``runtime/python/src/modd/link/datagram.py``:

* tcp: one DATA frame per slot (:func:`linkcost.data_frame_bytes`), split into
  segments of at most :data:`TCP_MSS` bytes, each with 52 B of IPv4 + TCP
  headers and one 52 B pure ACK back.
* udp and serial: consecutive slots packed into one datagram while the first
  slot has waited at most the accepted delay and the datagram fits the
  packet: ``type, config id, slot (u16le)`` (:data:`DGRAM_HEADER_BYTES`), the
  slots' values, a truncated HMAC tag (:data:`TAG_BYTES`). A slot larger than
  one packet goes as fragments, each with its own header, fragment byte and
  tag. udp adds 28 B of IPv4 + UDP headers per datagram; serial adds a CRC-16,
  COBS's overhead byte(s) and the 0x00 delimiter (:func:`serial_frame_bytes`).
* base to drone: nothing while nothing is lost on udp/serial but a keepalive
  PING every :data:`KEEPALIVE_S` seconds (the PubBroker's proof that the base
  station still listens).
* the link's own control traffic, drone to base (:mod:`.control`): STATUS
  every status period and a PONG per keepalive, in ``drone_to_base`` and
  ``packets_per_s`` (estimated; :attr:`LinkBudget.control` has the bound).

Every stream is assumed present in every window, as in ``linkcost``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from math import ceil
from typing import Any

from modd_contracts.link_wire_gen import CONTROL_TAG_BYTES as CONTROL_TAG_BYTES
from modd_contracts.link_wire_gen import DEFAULT_SERIAL_PACKET, DEFAULT_UDP_PACKET
from modd_contracts.link_wire_gen import TAG_BYTES as TAG_BYTES  # the datagrams' HMAC tags
from modd_contracts.types_gen import PlanLinkBudget

from .control import (
    CONTROL_HEADER_ABOUT,
    CONTROL_HEADER_MAX,
    KEEPALIVE_PAYLOAD,
    ControlInputs,
    ControlTraffic,
    control_traffic,
)
from .control import KEEPALIVE_S as KEEPALIVE_S
from .linkcost import (
    TCP_IP_HEADER_BYTES,
    UDP_IP_HEADER_BYTES,
    ceil_of_sums,
    data_frame_bytes,
)
from .schedule import Schedule

TRANSPORTS = ("tcp", "udp", "serial")
TCP_MSS = 1448  # Ethernet MTU 1500 - IPv4 20 - TCP 20 - timestamps 12
DGRAM_HEADER_BYTES = 4  # type, config id, slot u16le
FRAGMENT_BYTE = 1  # fragment index (high nibble) and count - 1 (low nibble)
SERIAL_CRC_BYTES = 2
DEFAULT_PACKET = {"tcp": TCP_MSS, "udp": DEFAULT_UDP_PACKET, "serial": DEFAULT_SERIAL_PACKET}
#: slots walked at most to predict packing and delays (bounded work per plan)
WALK_LIMIT = 400
#: a keepalive: control datagram type + counter (varint, ~2 B) + PING frame
#: (length, type, the SubBroker's 5 B payload) + tag
KEEPALIVE_BYTES = CONTROL_HEADER_ABOUT + 2 + KEEPALIVE_PAYLOAD
#: the STATUS room over tcp (docs/protocol.md, STATUS), frame bytes
TCP_STATUS_ROOM = 1400


def serial_frame_bytes(payload: int) -> int:
    """Bytes through the serial line for a datagram of ``payload`` bytes:
    COBS over payload + CRC-16 (one overhead byte per 254 started), then the
    0x00 delimiter.

    >>> serial_frame_bytes(80)
    84
    """
    body = payload + SERIAL_CRC_BYTES
    return body + 1 + body // 254 + 1


def wire_bytes(transport: str, payload: int) -> int:
    """One datagram of ``payload`` bytes on the wire of ``transport``."""
    if transport == "udp":
        return payload + UDP_IP_HEADER_BYTES
    if transport == "serial":
        return serial_frame_bytes(payload)
    raise ValueError(f"no datagrams on {transport!r}")


def datagram_capacity(transport: str, max_packet: int) -> int:
    """Largest datagram payload (header, values and tag) that fits one packet."""
    if transport == "udp":
        return max_packet
    n = max_packet - SERIAL_CRC_BYTES - 2
    while serial_frame_bytes(n) > max_packet:
        n -= 1
    return n


@dataclass(frozen=True)
class LinkSettings:
    """The model's link as the budget sees it."""

    transport: str = "tcp"
    rate_bps: int | None = None
    max_packet: int = TCP_MSS
    accepted_delay: Fraction = Fraction(1)

    @staticmethod
    def of(model: Mapping[str, Any], transport: str | None = None) -> LinkSettings:
        """From the model's ``link`` block (``transport`` overrides it, as
        ``modd up --link`` does)."""
        link = model.get("link", {})
        t = transport or link.get("transport", "tcp")
        if t not in TRANSPORTS:
            raise ValueError(f"unknown transport {t!r}; expected one of {', '.join(TRANSPORTS)}")
        packet = link.get("maxPacket", DEFAULT_PACKET[t]) if t != "tcp" else TCP_MSS
        return LinkSettings(
            t, link.get("rateBps"), packet, Fraction(link.get("acceptedDelayS", "1"))
        )


@dataclass(frozen=True)
class LinkBudget:
    """Predicted figures of one transport (bytes/s on the wire, both ways)."""

    settings: LinkSettings
    drone_to_base: float
    base_to_drone: float
    packets_per_s: float
    delays_s: dict[str, float]
    over_budget: tuple[str, ...] = field(default=())
    #: for the radio's air time (radio.py), not in the JSON: the walk's span
    #: (s), the size on the wire of each packet sent over it, drone to base,
    #: and each sent stream's value bytes/s with the subscriptions it serves
    span_s: float = 0.0
    packet_sizes: tuple[int, ...] = field(default=())
    streams: tuple[tuple[float, tuple[str, ...]], ...] = field(default=())
    #: the control traffic (control.py) as (wire bytes, packets per hour),
    #: estimated and bound, drone to base; its estimate is in drone_to_base
    #: and packets_per_s
    control: ControlTraffic | None = None
    control_about: tuple[tuple[int, float], ...] = field(default=())
    control_at_most: tuple[tuple[int, float], ...] = field(default=())

    @property
    def control_bytes_per_s(self) -> float:
        """Control traffic's estimated bytes/s on the wire, drone to base."""
        return sum(size * n for size, n in self.control_about) / 3600

    @property
    def control_bound_bytes_per_s(self) -> float:
        """Control traffic's bytes/s at most (while the instruments' states hold)."""
        return sum(size * n for size, n in self.control_at_most) / 3600

    @property
    def data_packets_per_s(self) -> float:
        """DATA packets per second (without the control traffic's)."""
        return self.packets_per_s - sum(n for _, n in self.control_about) / 3600

    @property
    def data_to_base(self) -> float:
        """DATA bytes/s on the wire, drone to base (the streams' share)."""
        return self.drone_to_base - self.control_bytes_per_s

    @property
    def share(self) -> float | None:
        rate = self.settings.rate_bps
        return self.drone_to_base / rate if rate else None

    @property
    def error(self) -> str | None:
        rate = self.settings.rate_bps
        if rate is None or self.drone_to_base <= rate:
            return None
        names = ", ".join(self.over_budget)
        return (
            f"the plan needs {self.drone_to_base:.1f} B/s on the {self.settings.transport} "
            f"link, more than its {rate} B/s; the subscriptions that exceed the budget: "
            f"{names}"
        )

    def to_json(self) -> PlanLinkBudget:
        s = self.settings
        share = self.share
        out: PlanLinkBudget = {
            "transport": s.transport,  # type: ignore[typeddict-item]  # a word the settings checked
            "rate_bps": s.rate_bps,
            "max_packet": s.max_packet,
            "accepted_delay_s": float(s.accepted_delay),
            "drone_to_base": round(self.drone_to_base, 3),
            "base_to_drone": round(self.base_to_drone, 3),
            "packets_per_s": round(self.packets_per_s, 6),
            "share": round(share, 6) if share is not None else None,
            "delays_s": {k: round(v, 6) for k, v in self.delays_s.items()},
            "over_budget": list(self.over_budget),
            "error": self.error,
        }
        c = self.control
        if c is not None:  # the control traffic's figures (absent without any)
            out["control"] = {
                "status_period_s": c.status_period_s,
                "bytes_per_s": round(self.control_bytes_per_s, 3),
                "packets_per_s": round(sum(n for _, n in self.control_about) / 3600, 6),
                "bound_bytes_per_s": round(self.control_bound_bytes_per_s, 3),
            }
        return out


#: One walked slot: (date µs, value bytes, stream count, distinct periods due).
WalkedSlot = tuple[int, int, int, list[int]]


def exact_sum(values: Iterable[Fraction]) -> Fraction:
    """``sum(values, Fraction(0))``, exactly, with one Fraction addition per
    distinct denominator (a plan's window sizes repeat few): the numerators
    of each denominator are added as integers, each distinct object's once
    times its count (a Fraction's numerator and denominator are properties;
    each object is held while counted, so its ``id`` is not reused)."""
    seen: dict[int, list[Any]] = {}
    for v in values:
        entry = seen.get(id(v))
        if entry is None:
            seen[id(v)] = [v, 1]
        else:
            entry[1] += 1
    by_den: dict[int, int] = {}
    for v, count in seen.values():
        d = v.denominator
        by_den[d] = by_den.get(d, 0) + v.numerator * count
    return sum((Fraction(n, d) for d, n in by_den.items()), Fraction(0))


def _walk_limit(schedule: Schedule, delay: Fraction) -> int:
    """Slots walked: one hyperperiod, or 20 accepted delays, at most WALK_LIMIT."""
    m = schedule.messages_per_hyperperiod
    per_s = Fraction(m) / schedule.hyperperiod
    return min(max(m, ceil(20 * delay * per_s)), WALK_LIMIT)


def _slot_walk(
    schedule: Schedule, window_bytes: Sequence[Fraction], delay: Fraction, carry: bool = False
) -> list[WalkedSlot]:
    """The first slots: one hyperperiod, or more until they span 20 accepted
    delays (so that packing reaches its steady state), at most
    :data:`WALK_LIMIT` slots (beyond, the walk is a sample of the schedule's
    start). Streams of one period are due together: each slot carries its
    periods, not its stream ids. A slot's value bytes are its sizes' sum
    rounded up, or with ``carry`` (mean sizes, calibration.py) rounded so
    that the walk's running total stays within a byte of the exact one:
    slots of 5.5 B alternate 6 and 5, as the real values' sizes vary. The
    walk goes on for one accepted delay past the limit, so that its last
    datagram is whole (:func:`_datagrams`' ``cut_us``; tcp drops those slots)."""
    by_period: dict[int, list[int]] = {}
    for i, p in enumerate(schedule.periods_us):
        by_period.setdefault(p, []).append(i)
    period_bytes = {p: exact_sum(window_bytes[i] for i in ids) for p, ids in by_period.items()}
    m = schedule.messages_per_hyperperiod
    if m == 0:
        return []
    limit = _walk_limit(schedule, delay)
    out: list[WalkedSlot] = []
    ceil_sum = ceil_of_sums(period_bytes)
    counts = {p: len(ids) for p, ids in by_period.items()}
    total, emitted = Fraction(0), 0
    end_us: int | None = None  # with carry: one accepted delay past the limit
    for index, date, due in schedule.iter_due_periods():
        if index >= limit:  # one accepted delay more (at most as many slots again)
            if index >= 2 * limit:
                break
            if end_us is None:
                end_us = out[-1][0] + int(delay * 1_000_000)
            if date > end_us:
                break
        if carry:
            total += sum((period_bytes[p] for p in due), Fraction(0))
            values = ceil(total) - emitted
            emitted += values
        else:
            values = ceil_sum(due)
        out.append((date, values, sum(counts[p] for p in due), due))
    return out


def _tcp(
    settings: LinkSettings, slots: list[WalkedSlot], span_s: float, sizes: list[int]
) -> tuple[float, float, float, dict[int, float]]:
    wire = 0
    segments = 0
    for _, values, count, _ in slots:
        frame = data_frame_bytes(values, count)
        segs = ceil(frame / TCP_MSS)
        segments += segs
        wire += frame + segs * TCP_IP_HEADER_BYTES
        sizes += [min(TCP_MSS, frame - k * TCP_MSS) + TCP_IP_HEADER_BYTES for k in range(segs)]
    rate = settings.rate_bps
    delays: dict[int, float] = {}  # per period
    for _, values, count, due in slots:
        air = (data_frame_bytes(values, count) + TCP_IP_HEADER_BYTES) / rate if rate else 0.0
        for p in due:
            delays[p] = max(delays.get(p, 0.0), air)
    return wire / span_s, segments * TCP_IP_HEADER_BYTES / span_s, segments / span_s, delays


def _datagrams(
    settings: LinkSettings,
    slots: list[WalkedSlot],
    span_s: float,
    sizes: list[int],
    cut_us: int | None = None,
) -> tuple[float, float, float, dict[int, float], float]:
    """Pack slots as the PubBroker does: a datagram holds consecutive slots
    while its first slot has waited at most the accepted delay and it fits
    the packet; it is sent at its last slot's date. With ``cut_us`` the
    datagrams that start after it are left out and the rates are over the
    span of those counted (the last one whole, not cut by the walk's end);
    the span used is returned last."""
    t = settings.transport
    cap = datagram_capacity(t, settings.max_packet)
    room = cap - DGRAM_HEADER_BYTES - TAG_BYTES
    delay_us = settings.accepted_delay * 1_000_000
    rate = settings.rate_bps
    wire = 0
    packets = 0
    delays: dict[int, float] = {}  # per period
    group: list[WalkedSlot] = []

    def flush() -> None:
        nonlocal wire, packets
        if not group:
            return
        values = sum(v for _, v, _, _ in group)
        size = DGRAM_HEADER_BYTES + values + TAG_BYTES
        bytes_on_wire = wire_bytes(t, size)
        wire += bytes_on_wire
        sizes.append(bytes_on_wire)
        packets += 1
        sent = group[-1][0]
        air = bytes_on_wire / rate if rate else 0.0
        for date, _, _, due in group:
            for p in due:
                delays[p] = max(delays.get(p, 0.0), (sent - date) / 1e6 + air)
        group.clear()

    for slot in slots:
        date, values, _, due = slot
        if cut_us is not None and date > cut_us:
            closes = not group or date - group[0][0] > delay_us
            if closes or values > room or sum(v for _, v, _, _ in group) + values > room:
                break  # this slot would start a datagram after the cut
        span_s = date / 1e6 if cut_us is not None else span_s
        if values > room:  # one slot larger than a packet: fragments
            flush()
            per = room - FRAGMENT_BYTE
            n = ceil(values / per)
            size = n * (DGRAM_HEADER_BYTES + FRAGMENT_BYTE + TAG_BYTES) + values
            fragments = [
                wire_bytes(
                    t, DGRAM_HEADER_BYTES + FRAGMENT_BYTE + TAG_BYTES + min(per, values - k * per)
                )
                for k in range(n)
            ]
            wire += sum(fragments)
            sizes += fragments
            packets += n
            air = wire_bytes(t, size // n) * n / rate if rate else 0.0
            for p in due:
                delays[p] = max(delays.get(p, 0.0), air)
            continue
        if group and (
            date - group[0][0] > delay_us or sum(v for _, v, _, _ in group) + values > room
        ):
            flush()
        group.append(slot)
    flush()
    keepalive = wire_bytes(t, KEEPALIVE_BYTES) / KEEPALIVE_S
    return wire / span_s, keepalive, packets / span_s, delays, span_s


def link_budget(
    settings: LinkSettings,
    schedule: Schedule,
    window_bytes: Sequence[Fraction],
    subscribers_of: Sequence[Sequence[str]],
    subscriptions: Sequence[str],
    carry: bool = False,
    control: ControlInputs | None = None,
) -> LinkBudget:
    """The budget of ``settings``'s transport for a schedule whose sent
    stream ``i`` carries ``window_bytes[i]`` per window and serves the
    subscribers ``subscribers_of[i]`` (directly or through a derived stream).
    ``subscriptions`` lists every subscriber, each of which gets a delay.
    ``carry``: the window bytes are means, slots rounded as :func:`_slot_walk`.
    ``control``: the control traffic's inputs (None: none counted)."""
    slots = _slot_walk(schedule, window_bytes, settings.accepted_delay, carry)
    if not slots:
        return LinkBudget(settings, 0.0, 0.0, 0.0, dict.fromkeys(subscriptions, 0.0))
    span_s = slots[-1][0] / 1e6  # slot dates start after 0: the walk covers (0, last]
    sizes: list[int] = []
    if settings.transport == "tcp":  # one frame a slot: nothing cut (carry's extra slots off)
        slots = slots[: _walk_limit(schedule, settings.accepted_delay)]
        span_s = slots[-1][0] / 1e6
        down, up, packets, period_delay = _tcp(settings, slots, span_s, sizes)
    else:
        cut = slots[min(len(slots), _walk_limit(schedule, settings.accepted_delay)) - 1][0]
        down, up, packets, period_delay, span_s = _datagrams(settings, slots, span_s, sizes, cut)
    delays = dict.fromkeys(subscriptions, 0.0)
    for i, subs in enumerate(subscribers_of):
        d = period_delay.get(schedule.periods_us[i], 0.0)
        for s in subs:
            delays[s] = max(delays.get(s, 0.0), d)
    streams = tuple(
        (float(b) / (p / 1e6), tuple(subs))
        for b, p, subs in zip(window_bytes, schedule.periods_us, subscribers_of, strict=True)
    )
    ctl = _control(settings, schedule, control, down, packets)
    if ctl is not None:
        down += sum(size * n for size, n in ctl[1]) / 3600
        packets += sum(n for _, n in ctl[1]) / 3600
    return LinkBudget(
        settings,
        down,
        up,
        packets,
        delays,
        _over_budget(settings, down, schedule, window_bytes, subscribers_of),
        span_s,
        tuple(sizes),
        streams,
        *(ctl if ctl is not None else (None, (), ())),
    )


ControlWire = tuple[ControlTraffic, tuple[tuple[int, float], ...], tuple[tuple[int, float], ...]]


def _control(
    settings: LinkSettings,
    schedule: Schedule,
    inputs: ControlInputs | None,
    down: float,
    packets_per_s: float,
) -> ControlWire | None:
    """The control traffic and its (wire bytes, packets per hour), estimated
    and bound: over udp/serial each frame in a CONTROL datagram of its own,
    over tcp in a segment of its own (a STATUS mostly rides in a DATA one)."""
    if inputs is None:
        return None
    t = settings.transport
    h = schedule.hyperperiod
    slots_per_s = float(schedule.messages_per_hyperperiod / h) if h else 0.0
    if t == "tcp":
        ctl = control_traffic(inputs, TCP_STATUS_ROOM, slots_per_s, down, packets_per_s)
        about = tuple((TCP_IP_HEADER_BYTES + f, n) for f, n in ctl.about)
        return ctl, about, tuple((TCP_IP_HEADER_BYTES + f, n) for f, n in ctl.at_most)
    room = datagram_capacity(t, settings.max_packet) - CONTROL_HEADER_MAX
    ctl = control_traffic(inputs, room, slots_per_s, down, packets_per_s)
    about = tuple((wire_bytes(t, CONTROL_HEADER_ABOUT + f), n) for f, n in ctl.about)
    at_most = tuple((wire_bytes(t, CONTROL_HEADER_MAX + f), n) for f, n in ctl.at_most)
    return ctl, about, at_most


def _over_budget(
    settings: LinkSettings,
    total: float,
    schedule: Schedule,
    window_bytes: Sequence[Fraction],
    subscribers_of: Sequence[Sequence[str]],
) -> tuple[str, ...]:
    """The subscriptions of the most expensive sent streams (value bytes/s),
    in that order, until dropping them brings the plan under the budget."""
    rate = settings.rate_bps
    if rate is None or total <= rate:
        return ()
    cost = sorted(
        (
            (float(b) / (p / 1e6), i)
            for i, (b, p) in enumerate(zip(window_bytes, schedule.periods_us, strict=True))
        ),
        reverse=True,
    )
    # headers scale with the packets; values are what a subscription adds
    excess = total - rate
    names: list[str] = []
    for c, i in cost:
        for s in subscribers_of[i]:
            if s not in names:
                names.append(s)
        excess -= c
        if excess <= 0:
            break
    return tuple(names)


def budget_lines(budget: LinkBudget) -> list[str]:
    """The budget for a person (``modd plan``'s text output)."""
    s = budget.settings
    headers = {"tcp": "IP+TCP headers", "udp": "IP+UDP headers", "serial": "COBS+CRC framing"}[
        s.transport
    ]
    lines = [
        "",
        f"link budget ({s.transport}, packet {s.max_packet} B, accepted delay "
        f"{float(s.accepted_delay):g} s): {budget.drone_to_base:.1f} B/s drone->base, "
        f"{budget.base_to_drone:.1f} B/s base->drone ({headers} included), "
        f"{budget.packets_per_s:.3f} packets/s",
    ]
    c = budget.control
    if c is not None:
        status = f"STATUS every {c.status_period_s} s" if c.status_period_s else "no STATUS"
        lines.append(
            f"  of which control {budget.control_bytes_per_s:.1f} B/s ({status}, a PONG every "
            f"{KEEPALIVE_S} s; at most {budget.control_bound_bytes_per_s:.1f} B/s)"
        )
    share = budget.share
    if share is not None:
        lines.append(f"  {100 * share:.1f} % of the radio's {s.rate_bps} B/s")
    lines += [f"  delay {name}: {d:.3f} s" for name, d in budget.delays_s.items()]
    if budget.error:
        lines += ["", f"OVER BUDGET: {budget.error}"]
    return lines
