"""What a simulated instrument writes on its wire, from the values the
simulator gives its topics: the model's mapping run backwards
(``raw = (value - offset) / scale``), laid out as the NMEA sentences, ASCII
lines or Modbus replies ``modd-sensors`` reads, so the demo and the tests run
the real reader.

Example::

    lines = nmea_lines(plan, {"usv.gnss.lat": 47.7}, time.time())
    # ['$GPGGA,101500.00,4742.0000,N,,,,,,,,,,,*..', '$GPZDA,...']
"""

from __future__ import annotations

import struct
import time
from collections.abc import Mapping

from modd_model.vocabulary import NMEA_SENTENCES

from ..sensors import modbus
from ..sensors.ascii import Column
from ..sensors.nmea import sentence
from ..sensors.plan import Mapping as TopicMapping
from ..sensors.plan import Register, SensorPlan

TALKER = "GP"
# A simulated receiver has a fix: the validity fields say so (modd.sensors.validity).
VALID_FIX = {
    "GGA": {5: "1"},
    "GNS": {5: "AA"},
    "GSA": {0: "A", 1: "3"},
    "RMC": {11: "A"},
    "GLL": {6: "A"},
    "VTG": {8: "A"},
}


def _raw(m: TopicMapping, value: float) -> float:
    return (value - m.offset) / m.scale


def _coordinate(value: float, degree_digits: int) -> tuple[str, str]:
    hemi = ("N" if value >= 0 else "S") if degree_digits == 2 else ("E" if value >= 0 else "W")
    degrees, minutes = divmod(round(abs(value) * 60, 4), 60)  # 59.99996' is 1 degree on
    return f"{int(degrees):0{degree_digits}d}{minutes:07.4f}", hemi


def _stamp(kind: str, now: float) -> str:
    t = time.gmtime(now)
    if kind == "time":
        return time.strftime("%H%M%S", t) + f".{int(now * 100) % 100:02d}"
    return time.strftime("%d%m%y", t) if kind == "date" else "A" if kind == "status" else ""


def _index(kind: str, field: str) -> int:
    names = list(NMEA_SENTENCES[kind])
    return names.index(field) if field in names else int(field[1:]) - 1


def _put(fields: list[str], kind: str, i: int, m: TopicMapping, value: float) -> None:
    table = list(NMEA_SENTENCES[kind].values())
    fields += [""] * (i + 2 - len(fields))
    what = table[i % len(table)]
    if what in ("latitude", "longitude"):
        fields[i], fields[i + 1] = _coordinate(_raw(m, value), 2 if what == "latitude" else 3)
    else:
        fields[i] = f"{_raw(m, value):.4f}"


def _quadruplet(m: TopicMapping) -> bool:
    """An XDR variable whose condition picks its quadruplet (``where id = NAME``)."""
    quad = list(NMEA_SENTENCES["XDR"])
    c = m.condition
    return m.where[0] == "XDR" and c is not None and c.place in quad and m.where[1] in quad  # type: ignore[index]


def _fields(kind: str, mapped: list[tuple[TopicMapping, float]], now: float) -> list[str]:
    table = list(NMEA_SENTENCES[kind].items())
    fields = [_stamp(k, now) for _, k in table]
    for i, text in VALID_FIX.get(kind, {}).items():
        fields[i] = text
    for m, value in mapped:
        if not _quadruplet(m):
            _put(fields, kind, _index(kind, m.where[1]), m, value)  # type: ignore[index]
        if m.condition is not None and m.condition.op == "=" and not _quadruplet(m):
            fields[_index(kind, str(m.condition.place))] = m.condition.value
    if kind != "XDR":
        return fields[: len(table)]
    if all(_quadruplet(m) for m, _ in mapped):
        fields = []  # only named transducers: no empty first quadruplet
    fields += [""] * (-len(fields) % 4)  # groups of four; a named transducer in its own
    for m, value in mapped:
        if _quadruplet(m) and m.condition is not None:
            group = [""] * 4
            group[_index("XDR", str(m.condition.place))] = m.condition.value
            _put(group, "XDR", _index("XDR", m.where[1]), m, value)  # type: ignore[index]
            fields += group[:4]
    return fields


def _sentence_key(m: TopicMapping) -> tuple[str, str]:
    """Variables written in one sentence: by type, and by the condition they need met
    (MWV with reference T and with R are two sentences; XDR quadruplets share one)."""
    c = m.condition
    if c is None or c.op != "=" or _quadruplet(m):
        return m.where[0], ""  # type: ignore[index]
    return m.where[0], f"{c.place}={c.value}"  # type: ignore[index]


def nmea_lines(plan: SensorPlan, values: Mapping[str, float], now: float) -> list[str]:
    """One sentence per sentence type the sensor's variables read (and a ZDA when
    the model stamps with the instrument's clock)."""
    # the time first, as receivers start an epoch with it
    by_kind: dict[tuple[str, str], list[tuple[TopicMapping, float]]] = (
        {("ZDA", ""): []} if plan.instrument_clock else {}
    )
    for m in plan.mappings:
        if m.topic in values:
            by_kind.setdefault(_sentence_key(m), []).append((m, values[m.topic]))
    out = []
    for (kind, _), mapped in by_kind.items():
        fields = _fields(kind, mapped, now)
        if kind == "ZDA":
            t = time.gmtime(now)
            fields[1:6] = [f"{t.tm_mday:02d}", f"{t.tm_mon:02d}", str(t.tm_year), "00", "00"]
        out.append(sentence(TALKER, kind, fields))
    return out


def ascii_line(
    plan: SensorPlan, values: Mapping[str, float], mappings: list[TopicMapping] | None = None
) -> str:
    """One line with the sensor's columns and key=value pairs (a pattern is not inverted:
    write the model's separator-and-key form), with the ``=`` conditions of ``mappings``
    (all the sensor's by default) met."""
    columns: dict[int, str] = {}
    pairs: list[str] = []
    for m in plan.mappings if mappings is None else mappings:
        if m.topic not in values:
            continue
        c = m.condition
        if c is not None and c.op == "=":
            if isinstance(c.place, Column):
                columns[c.place.number] = c.value
            else:
                pairs.append(f"{c.place.name}={c.value}")  # type: ignore[union-attr]
        text = f"{_raw(m, values[m.topic]):.4f}"
        if isinstance(m.where, Column):
            columns[m.where.number] = text
        else:
            pairs.append(f"{m.where.name}={text}")  # type: ignore[union-attr]
    cells = [columns.get(i, "0") for i in range(1, max(columns, default=0) + 1)] + pairs
    return (" " if plan.line.separator == " " else plan.line.separator).join(cells)


def ascii_lines(plan: SensorPlan, values: Mapping[str, float]) -> list[str]:
    """One line per record type the variables' conditions name (a CTD's S and B
    lines), the unconditioned variables in each."""
    kinds: dict[str, list[TopicMapping]] = {}
    plain = [m for m in plan.mappings if m.condition is None or m.condition.op != "="]
    for m in plan.mappings:
        if m not in plain and m.condition is not None:
            kinds.setdefault(f"{m.condition.place}={m.condition.value}", []).append(m)
    groups = [plain + ms for ms in kinds.values()] or [plain]
    return [ascii_line(plan, values, g) for g in groups]


def _words(r: Register, raw: float) -> list[int]:
    fmt = {"int16": ">h", "uint16": ">H", "int32": ">i", "uint32": ">I", "float32": ">f"}[r.type]
    number: float | int = raw if r.type == "float32" else round(raw)
    try:
        data = struct.pack(fmt, number)
    except struct.error:  # beyond the register's range: what a saturating device sends
        data = b"\xff" * struct.calcsize(fmt)
    words = list(struct.unpack(f">{len(data) // 2}H", data))
    return words[::-1] if r.order == "little" else words


def registers(plan: SensorPlan, values: Mapping[str, float]) -> dict[tuple[int, int, int], int]:
    """(unit, function, address) → word of every mapped register."""
    out: dict[tuple[int, int, int], int] = {}
    for m in plan.mappings:
        r = m.where
        if isinstance(r, Register) and m.topic in values:
            for i, w in enumerate(_words(r, _raw(m, values[m.topic]))):
                out[(r.unit, modbus.TABLE_FUNCTION[r.table], r.address + i)] = w
    return out


def modbus_reply(request: bytes, regs: Mapping[tuple[int, int, int], int]) -> bytes | None:
    """A device's answer to one read request (exception 2 for an unknown register);
    None for a request that is not for a read or fails its CRC (a device stays silent)."""
    if len(request) != 8 or modbus.crc16(request[:-2]) != struct.unpack("<H", request[-2:])[0]:
        return None
    unit, function, address, count = struct.unpack(">BBHH", request[:6])
    if function not in (modbus.HOLDING, modbus.INPUT):
        return None
    try:
        words = [regs[(unit, function, address + i)] for i in range(count)]
        pdu = struct.pack(f">BBB{count}H", unit, function, 2 * count, *words)
    except KeyError:
        pdu = bytes([unit, function | 0x80, 2])
    return pdu + struct.pack("<H", modbus.crc16(pdu))
