"""The configs a datagram session decodes (the running one, and the one it
replaced until its last slots are in), their gaps and NACKs, and the radio's
counters (docs/protocol.md, "NACK"; docs/subbroker.md, "Status").

>>> runs = Runs(delay_s=1.0, radio=RadioCounters(), clock=SystemClock())  # doctest: +SKIP
>>> runs.accept(config, ack, key); runs.on_datagram(raw)                  # doctest: +SKIP
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

from modd_plan.schedule import Schedule

from modd.link import codec
from modd.link.datagram import encode_nack
from modd.link.dgreceiver import DatagramReceiver
from modd.link.frames import Config, ConfigAck, ProtocolError, Value
from modd.link.receiver import Window
from modd.link.schedule import SlotIterator

from .linkhooks import Clock

MAX_NACK_ASKS = 5
PUBBROKER_COUNTS = (
    "datagrams_sent",
    "datagrams_resent",
    "nacks",
    "slots_dropped",
    "forged",
    "replayed",
)
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
    foreign: int = 0  # from an address the session is not bound to (logged, not in the status)
    heard_elsewhere: int = 0  # forwarded by other stations (docs/fleet.md, "Diversity reception")
    heard_elsewhere_used: int = 0  # ... that brought what this station's modem missed
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
            rest = rest[f.size :]
    except ProtocolError:
        return None
    return out or None


class Runs:
    """The configs whose DATA datagrams are decoded, by config id."""

    def __init__(self, delay_s: float, radio: RadioCounters, clock: Clock) -> None:
        self.delay_s = delay_s
        self._configured_delay_s = delay_s
        self._radio = radio
        self._clock = clock
        self.key = b""
        self.old_key = b""  # the last session's: its datagrams may still be on the way
        self.by_id: dict[int, _Run] = {}

    def rekey(self, key: bytes) -> None:
        self.key = key
        for run in self.by_id.values():
            run.receiver.key = key

    def accept(self, config: Config, ack: ConfigAck, key: bytes) -> None:
        """An acked CONFIG: its DATA is decoded from now on, and the running config's
        last slots (up to the new epoch, packed before the switch, up to the old
        accepted delay late) still are: the previous run is kept until the next
        config replaces it."""
        self.key = key
        self.delay_s = (
            self._configured_delay_s
            if config.accepted_delay_ms is None
            else config.accepted_delay_ms / 1000
        )
        periods = [s.period_us for s in config.streams]
        receiver = DatagramReceiver(key, config.config_id, periods, config.kinds())
        receiver.gaps.max_asks = MAX_NACK_ASKS
        runs = {
            cid: run
            for cid, run in self.by_id.items()
            if run.end_ns is None and cid != config.config_id
        }
        for run in runs.values():
            run.end_ns = ack.epoch_ns
        runs[config.config_id] = _Run(
            config, ack.epoch_ns, receiver, Schedule.from_periods_us(periods)
        )
        self.by_id = runs

    def joined_at(self, config_id: int, slot: int) -> None:
        """A config joined while it runs (adopted from another station: handover.py):
        its slot numbers, 16 bits on the air, are read near ``slot`` (that station's
        last), not near 0."""
        run = self.by_id.get(config_id)
        if run is not None:
            run.receiver.expected = slot

    def on_datagram(self, raw: bytes) -> list[list[Window]] | None:
        """The windows of each slot a DATA datagram holds, or None when it is refused
        (counted: unknown config, forged, replayed, malformed)."""
        run = self.by_id.get(raw[1])
        if run is None:
            self._radio.unknown_config += 1
            return None
        rx = run.receiver
        now = self._clock.monotonic()
        before = (rx.stats.forged, rx.stats.replayed, rx.stats.malformed)
        slots = rx.on_datagram(raw, now)
        if not slots and rx.stats.forged > before[0] and self.old_key:
            rx.key, rx.stats.forged = self.old_key, rx.stats.forged - 1  # the last session's
            slots = rx.on_datagram(raw, now)
            rx.key = self.key
        self._radio.forged += rx.stats.forged - before[0]
        self._radio.replayed += rx.stats.replayed - before[1]
        self._radio.malformed += rx.stats.malformed - before[2]
        if not slots:
            return None
        if run.asks and slots[0][0] <= run.asked_slot < slots[0][0] + len(slots):
            run.recovered += len(slots)  # the answer to an overdue NACK
        last = run.epoch_ns / 1e9 + run.schedule.slot_date_us(slots[-1][0]) / 1e6
        late = self._clock.time_ns() / 1e9 - last
        run.lateness = late if run.lateness is None else min(run.lateness, late)
        return _windows(run, slots)

    def nacks(self, now: float, every: float) -> list[bytes]:
        """The NACK frames due now: the gaps' ranges (under the session's one control
        counter: the receiver's own NACK datagrams would reuse its numbers, dropped as
        replays), and the next slot of a run once its datagram is overdue."""
        out: list[bytes] = []
        for run in self.by_id.values():
            ranges = run.receiver.gaps.due(now, every)
            if ranges:
                out.append(encode_nack(ranges))
            if self._overdue(run, now, every):
                out.append(encode_nack([(run.asked_slot, 1)]))
        self._radio.nacks += len(out)
        return out

    def _overdue(self, run: _Run, now: float, every: float) -> bool:
        """Is the next expected slot overdue (sent at the latest its date + the accepted
        delay, arriving the learnt lateness after)? A lost datagram is asked for at once,
        not when the next one shows the gap. Every ``every`` s, at most MAX_NACK_ASKS times."""
        nxt = run.receiver.gaps.next
        if run.lateness is None or nxt < 0:
            return False
        date_ns = run.epoch_ns + run.schedule.slot_date_us(nxt) * 1000
        if run.end_ns is not None and date_ns >= run.end_ns:
            return False  # a replaced config: no slot of it after the switch
        if nxt != run.asked_slot:
            run.asked_slot, run.asks, run.asked_at = nxt, 0, float("-inf")
        if run.asks >= MAX_NACK_ASKS or now - run.asked_at < every:
            return False
        due = (
            run.epoch_ns / 1e9
            + run.schedule.slot_date_us(nxt) / 1e6
            + self.delay_s
            + run.lateness
            + OVERDUE_GRACE_S
        )
        if self._clock.time_ns() / 1e9 < due:
            return False
        run.asks += 1
        run.asked_at = now
        return True

    def sample_wire(self, now: float, wire_in: int, wire_out: int) -> None:
        """The port's wire counters, kept 10 s for the rates of the status."""
        rates = self._radio._rates
        if not rates or now - rates[-1][0] >= 0.25:
            rates.append((now, wire_in, wire_out))
        while rates and rates[0][0] < now - 10.0:
            rates.popleft()

    def status(self, r: RadioCounters, corrupt: int) -> dict[str, Any]:
        """The radio fields of the status (docs/subbroker.md, "Status") but the
        transport, the accepted delay and the PubBroker's counters."""
        rx = [run.receiver for run in self.by_id.values()]
        received = sum(x.stats.slots for x in rx)
        recovered = sum(x.gaps.recovered for x in rx) + sum(
            run.recovered for run in self.by_id.values()
        )
        lost = sum(x.gaps.lost for x in rx)
        missing = sum(x.gaps.missing for x in rx)
        seen = received + lost + missing
        rates = list(r._rates)
        down = up = None
        if len(rates) >= 2 and rates[-1][0] > rates[0][0]:
            span = rates[-1][0] - rates[0][0]
            down = round((rates[-1][1] - rates[0][1]) / span, 1)
            up = round((rates[-1][2] - rates[0][2]) / span, 1)
        return {
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
            "malformed": r.malformed + corrupt,
            "unknown_config": r.unknown_config,
            "handshakes": r.handshakes,
            **(
                {
                    "heard_elsewhere": r.heard_elsewhere,
                    "heard_elsewhere_used": r.heard_elsewhere_used,
                }
                if r.heard_elsewhere
                else {}
            ),
        }


def _windows(run: _Run, slots: list[tuple[int, list[Value]]]) -> list[list[Window]]:
    """The windows of each slot, an empty one (every stream absent: no sample, an
    ingest stall) included: it arrived, so its windows are not gaps and the derived
    windows it is part of complete; the delivery gives a sent stream's subscribers
    nothing for it (as over tcp, which does not send it; docs/subbroker.md)."""
    it = SlotIterator([s.period_us for s in run.config.streams])
    it.skip_to(slots[0][0])
    out: list[list[Window]] = []
    for index, values in slots:
        it.skip_to(index)
        slot = next(it)
        end = run.epoch_ns + slot.offset_us * 1000
        out.append(
            [
                Window(
                    run.config.config_id,
                    index,
                    sid,
                    end - run.config.streams[sid].period_us * 1000,
                    end,
                    v,
                )
                for sid, v in zip(slot.streams, values, strict=True)
            ]
        )
    return out
