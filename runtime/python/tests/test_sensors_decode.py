"""modd-sensors' logic apart from I/O: a model's instrument sensors → plans,
bytes → samples (however the bytes are cut), every bad line counted and
giving no value; Modbus frames and register words against pymodbus."""

from __future__ import annotations

import dataclasses
import struct
from typing import Any

import pynmea2  # type: ignore[import-untyped]
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from modd.sensors import modbus
from modd.sensors.decode import LineDecoder, block_samples, blocks
from modd.sensors.health import Health
from modd.sensors.plan import SensorPlan, plan_sensors
from modd_model import parse_text
from pymodbus.client import ModbusSerialClient
from pymodbus.framer import FramerRTU

MODEL = r"""
Drone usv { Sensors {
    Sensor gnss kind nmea on "/dev/gnss" measures {
        lat("deg", float64) from sentence GGA.lat; lon("deg", float64) from sentence GGA.lon;
        depth(METER) from sentence DBT.depth_meters;
        heading("deg") from sentence HDT.heading scale 1 offset 0.5;
    }
    Sensor ctd kind ascii on "/dev/ctd" measures {
        t(DEGREE_CELSIUS) from column 1; c("mS/cm") from key "C" scale 0.1;
    }
    Sensor sonde kind modbus on "/dev/sonde" { baud = 19200; parity = even; } measures {
        ph(NONE) from register 100 float32; temp(DEGREE_CELSIUS) from register 102 int16 scale 0.01;
        cond("uS/cm") from register 104 uint32 order little; o2(NONE) from register 3 uint16 unit 2;
        raw(NONE) from register 0 int16 table input;
    }
} }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers {
    Publisher nav(0.1, "usv.gnss.lat", "usv.gnss.lon", "usv.gnss.depth", "usv.gnss.heading");
    Publisher water(1.0, "usv.ctd.t", "usv.ctd.c", "usv.sonde.ph", "usv.sonde.temp",
                    "usv.sonde.cond", "usv.sonde.o2", "usv.sonde.raw");
}
"""


def _plans() -> dict[str, SensorPlan]:
    doc, _ = parse_text(MODEL)
    return {p.name: p for p in plan_sensors(doc)}


def _topics(samples: list[Any]) -> dict[str, float]:
    return {m.topic.rsplit(".", 1)[1]: v for m, _, v in samples}


def test_plan_of_the_model() -> None:
    plans = _plans()
    gnss, ctd, sonde = plans["gnss"], plans["ctd"], plans["sonde"]
    assert not gnss.instrument_clock and gnss.poll_s == pytest.approx(0.1)
    assert {m.publisher for m in gnss.mappings} == {"nav"}
    assert ctd.terminator == b"\n" and ctd.kind == "ascii"
    assert (sonde.device.baud, sonde.device.parity, sonde.poll_s) == (19200, "even", 1.0)


GGA = "$GNGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*59\r\n"
DBT = "$SDDBT,12.3,f,3.75,M,2.05,F*2D\r\n"
ZDA = "$GPZDA,201530.00,04,07,2002,00,00*60\r\n"


def _fixed(line: str) -> str:
    """``line`` with its right checksum (so that tests can write sentences by hand)."""
    body = line.strip()[1 : line.index("*")]
    return f"${body}*{pynmea2.NMEASentence.checksum(body):02X}\r\n"


@settings(max_examples=60)
@given(st.lists(st.integers(1, 30), min_size=1, max_size=12))
def test_nmea_bytes_cut_anywhere(cuts: list[int]) -> None:
    """The same samples whatever the reads' boundaries (a serial port returns any split)."""
    plan = _plans()["gnss"]
    stream = (GGA + _fixed(DBT) + "garbage\xff\r\n" + GGA[:30] + "\r\n").encode("latin-1")
    health = Health()
    dec = LineDecoder(plan, health)
    out, i, k = [], 0, 0
    while i < len(stream):
        n = cuts[k % len(cuts)]
        out += dec.feed(stream[i : i + n], 1_000)
        i, k = i + n, k + 1
    oracle = pynmea2.parse(GGA.strip(), check=True)
    assert _topics(out) == {
        "lat": pytest.approx(oracle.latitude),
        "lon": pytest.approx(oracle.longitude),
        "depth": 3.75,
    }
    assert (health.lines_ok, health.lines_bad) == (2, 2)  # garbage and the truncated GGA


def test_instrument_clock_from_zda() -> None:
    plan = dataclasses.replace(_plans()["gnss"], instrument_clock=True)
    dec = LineDecoder(plan, Health())
    zda = int(pynmea2.parse(ZDA.strip()).datetime.timestamp() * 1e9)
    now = zda + 10**9  # the computer's clock, near the instrument's (no rollover)
    assert dec.feed(GGA.encode(), now) == []  # no instrument date yet: held
    gga = pynmea2.parse(GGA.strip()).timestamp
    released = dec.feed(ZDA.encode(), now)
    day = zda - zda % 86_400_000_000_000
    own = day + (gga.hour * 3600 + gga.minute * 60 + gga.second) * 10**9
    assert [s[1] for s in released] == [own, own]  # lat and lon, at GGA's own time
    assert [s[1] for s in dec.feed(GGA.encode(), now + 500_000_000)] == [own, own]


def test_heading_scale_offset_and_empty_fields() -> None:
    health = Health()
    dec = LineDecoder(_plans()["gnss"], health)
    got = dec.feed((_fixed("$HEHDT,271.5,T*00") + _fixed("$HEHDT,,T*00")).encode(), 1)
    assert _topics(got) == {"heading": 272.0}
    assert (health.lines_ok, health.missing) == (2, 1)


def test_garbage_at_the_wrong_baud_rate_is_bounded_and_counted() -> None:
    """200 kB with no line end: dropped as overlong lines, memory bounded, nothing published."""
    health = Health()
    dec = LineDecoder(_plans()["gnss"], health)
    junk = bytes(range(256)).replace(b"\n", b"") * 800
    assert dec.feed(junk, 1) == []
    assert len(dec.splitter._buf) <= dec.splitter.max_line
    assert dec.feed(b"\r\n" + GGA.encode(), 1) != []  # the next good line after the junk
    assert health.lines_bad >= 1 and health.lines_ok == 1


def test_ascii_columns_keys_and_bad_lines() -> None:
    health = Health()
    dec = LineDecoder(_plans()["ctd"], health)
    got = dec.feed(b"12.5,C=451.0,x\r\n12.6,C=4\r\nS>\r\n13.0\r\nnan,C=1\r\n", 7)
    assert [(_topics([s]), s[1]) for s in got] == [
        ({"t": 12.5}, 7),
        ({"c": pytest.approx(45.1)}, 7),
        ({"t": 12.6}, 7),
        ({"c": pytest.approx(0.4)}, 7),
    ]
    assert (health.lines_ok, health.lines_bad) == (2, 3)  # prompt, missing key, NaN


def test_modbus_blocks_cover_every_register_once() -> None:
    reads = blocks(_plans()["sonde"])
    shape = sorted((b.unit, b.function, b.address, b.count) for b in reads)
    assert shape == [
        (1, modbus.HOLDING, 100, 6),
        (1, modbus.INPUT, 0, 1),
        (2, modbus.HOLDING, 3, 1),
    ]


def test_modbus_words_decode_as_pymodbus_does() -> None:
    client = ModbusSerialClient
    words = [
        *client.convert_to_registers(7.25, client.DATATYPE.FLOAT32),
        *client.convert_to_registers(-1234, client.DATATYPE.INT16),
        0,
        *client.convert_to_registers(123456, client.DATATYPE.UINT32, word_order="little"),
    ]
    block = next(b for b in blocks(_plans()["sonde"]) if b.address == 100)
    got = _topics(block_samples(block, words, 1))
    assert got == {"ph": 7.25, "temp": pytest.approx(-12.34), "cond": 123456}


@given(st.binary(min_size=1, max_size=64))
def test_crc_matches_pymodbus(data: bytes) -> None:
    """The same two bytes on the wire (pymodbus returns them as a big-endian number)."""
    assert struct.pack("<H", modbus.crc16(data)) == struct.pack(">H", FramerRTU.compute_CRC(data))


def test_replies_exceptions_and_corruption() -> None:
    words = [0x41C8, 0x0000]
    body = struct.pack(">BBB", 1, 3, 4) + struct.pack(">HH", *words)
    reply = body + struct.pack("<H", modbus.crc16(body))
    assert modbus.parse_reply(reply, 1, 3, 2) == words
    with pytest.raises(modbus.BadReply, match="CRC"):
        modbus.parse_reply(reply[:-1] + bytes([reply[-1] ^ 1]), 1, 3, 2)
    with pytest.raises(modbus.BadReply, match="unit"):
        modbus.parse_reply(reply, 2, 3, 2)
    exc = bytes([1, 0x83, 2])
    exc += struct.pack("<H", modbus.crc16(exc))
    assert modbus.reply_length(exc, 3) == 5
    with pytest.raises(modbus.ExceptionReply, match="illegal data address"):
        modbus.parse_reply(exc, 1, 3, 2)
