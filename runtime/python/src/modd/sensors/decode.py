"""The reader's logic apart from I/O: bytes of a line instrument → samples
(``LineDecoder``), Modbus registers → read blocks and samples
(``ModbusDecoder``), every refusal counted in the sensor's ``Health``. Nothing
here blocks or raises on any input.

Example::

    dec = LineDecoder(plan, health)
    for mapping, stamp_ns, value in dec.feed(b"$GPDPT,3.2,0.5*7E\\r\\n", time.time_ns()):
        publisher.publish(mapping.topic, stamp_ns, value)
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

from . import modbus, nmea
from .ascii import BadLine, cells, read
from .clock import HOLD_MAX, InstrumentClock
from .condition import ascii_holds, nmea_field
from .health import Health
from .lines import LineSplitter
from .plan import Mapping, Register, SensorPlan
from .validity import no_fix

Sample = tuple[Mapping, int, float]


class LineDecoder:
    """An ``nmea`` or ``ascii`` sensor's bytes → samples, stamped on receive (or,
    for an ``nmea`` sensor with ``clock = instrument``, with the sentence's own
    UTC time: ``clock.InstrumentClock``, samples held until its date is known)."""

    def __init__(self, plan: SensorPlan, health: Health, max_line: int | None = None) -> None:
        self.plan = plan
        self.health = health
        limit = max_line or (nmea.MAX_LINE if plan.kind == "nmea" else 4096)
        self.splitter = LineSplitter(plan.terminator, limit)
        self._dropped = 0  # overlong or undecodable lines already counted
        self.clock = InstrumentClock() if plan.instrument_clock else None
        self.held: deque[tuple[Mapping, int | None, float]] = (
            deque()
        )  # (mapping, time of day, value)
        self.by_sentence: dict[str, list[Mapping]] = {}
        for m in plan.mappings:
            if isinstance(m.where, tuple):
                self.by_sentence.setdefault(m.where[0], []).append(m)
        self.wanted = {m.topic: m.where for m in plan.mappings if not isinstance(m.where, tuple)}
        self.by_topic = {m.topic: m for m in plan.mappings}

    def feed(self, data: bytes, now_ns: int) -> list[Sample]:
        out: list[Sample] = []
        for line in self.splitter.feed(data):
            if line.strip():
                out += (
                    self._nmea(line, now_ns)
                    if self.plan.kind == "nmea"
                    else self._ascii(line, now_ns)
                )
        dropped = self.splitter.overlong + self.splitter.undecodable
        if dropped > self._dropped:
            self.health.bad("line too long or not text (garbage, wrong baud rate?)")
            self.health.lines_bad += dropped - self._dropped - 1
            self._dropped = dropped
        return out

    def _nmea(self, line: str, now_ns: int) -> list[Sample]:
        try:
            s = nmea.parse_sentence(line, self.plan.checksum_required)
        except nmea.BadSentence as exc:
            self.health.bad(str(exc))
            return []
        self.health.lines_ok += 1
        stamp: int | None = now_ns
        released: list[Sample] = []
        if self.clock is not None:
            known = self.clock.midnight_ns is not None
            stamp = self.clock.observe(s, now_ns)
            if not known and self.clock.midnight_ns is not None:
                released = self._release()
        mapped = [
            (m, f)
            for m in self.by_sentence.get(s.type, ())
            if (f := nmea_field(s, m.where[1], m.condition)) is not None  # type: ignore[index]
        ]
        if not mapped:  # no mapping, or none whose condition the sentence meets
            self.health.ignored += 1
            return released
        if (why := no_fix(s, self.plan.fix)) is not None:
            self.health.no_value(len(mapped), why, no_fix=True)
            return released
        values: list[tuple[Mapping, float]] = []
        for m, field in mapped:
            try:
                values.append((m, m.value(nmea.field_value(s, field))))
            except nmea.NoValue as exc:
                self.health.no_value(1, str(exc))
        if stamp is not None:
            if self.clock is not None:
                self.health.clock_offset_ms = (stamp - now_ns) // 1_000_000
            return released + [(m, stamp, v) for m, v in values]
        assert self.clock is not None
        self._hold(self.clock.pending_tod(s), values)
        return released

    def _hold(self, tod_ns: int | None, values: list[tuple[Mapping, float]]) -> None:
        """Keeps samples until the instrument states its date (at most HOLD_MAX)."""
        if tod_ns is None:
            self.health.no_value(len(values), "before the instrument's first time of day")
            return
        for m, v in values:
            if len(self.held) >= HOLD_MAX:
                self.held.popleft()
                self.health.no_value(1, "held too long: the instrument states no date (RMC/ZDA)")
            self.held.append((m, tod_ns, v))

    def _release(self) -> list[Sample]:
        assert self.clock is not None
        out = [(m, self.clock.on_date(tod), v) for m, tod, v in self.held if tod is not None]
        self.held.clear()
        return out

    def _ascii(self, line: str, now_ns: int) -> list[Sample]:
        try:
            c = cells(self.plan.line, line)
            wanted = {
                t: w for t, w in self.wanted.items() if ascii_holds(c, self.by_topic[t].condition)
            }
            got = read(c, wanted)  # type: ignore[arg-type]
        except BadLine as exc:
            self.health.bad(str(exc))
            return []
        self.health.lines_ok += 1
        if not wanted:  # a record of a type no variable reads
            self.health.ignored += 1
        return [(self.by_topic[t], now_ns, self.by_topic[t].value(v)) for t, v in got.items()]


@dataclass(frozen=True)
class Block:
    """One read request: ``count`` registers from ``address`` of one unit's table."""

    unit: int
    function: int
    address: int
    count: int
    mappings: tuple[Mapping, ...]

    def request(self) -> bytes:
        return modbus.read_request(self.unit, self.function, self.address, self.count)


def _reg(m: Mapping) -> Register:
    assert isinstance(m.where, Register)
    return m.where


def blocks(plan: SensorPlan) -> list[Block]:
    """The fewest read requests covering the sensor's registers (contiguous runs
    of one unit and table, at most 125 registers each)."""
    regs = sorted(plan.mappings, key=lambda m: (_reg(m).unit, _reg(m).table, _reg(m).address))
    out: list[Block] = []
    run: list[Mapping] = []

    def close() -> None:
        if run:
            r0 = _reg(run[0])
            end = max(_reg(m).address + modbus.WORDS[_reg(m).type] for m in run)
            out.append(
                Block(
                    r0.unit,
                    modbus.TABLE_FUNCTION[r0.table],
                    r0.address,
                    end - r0.address,
                    tuple(run),
                )
            )

    for m in regs:
        r = _reg(m)
        if run:
            r0 = _reg(run[0])
            if (r.unit, r.table) != (r0.unit, r0.table) or r.address + modbus.WORDS[
                r.type
            ] - r0.address > modbus.MAX_REGISTERS:
                close()
                run = []
        run.append(m)
    close()
    return out


def block_samples(block: Block, words: list[int], now_ns: int) -> list[Sample]:
    out: list[Sample] = []
    for m in block.mappings:
        r = _reg(m)
        i = r.address - block.address
        raw = modbus.decode_words(words[i : i + modbus.WORDS[r.type]], r.type, r.order)
        out.append((m, now_ns, m.value(raw)))
    return out
