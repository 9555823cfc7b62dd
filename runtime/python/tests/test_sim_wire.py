"""What the simulated instruments write (modd.sim.wire) is what modd-sensors
reads back: NMEA sentences checked by pynmea2 too, CSV lines, Modbus replies."""

from __future__ import annotations

import pynmea2  # type: ignore[import-untyped]
import pytest
from hypothesis import given
from hypothesis import strategies as st
from modd.sensors import modbus
from modd.sensors.decode import LineDecoder, block_samples, blocks
from modd.sensors.health import Health
from modd.sensors.plan import SensorPlan, plan_sensors
from modd.sim.wire import ascii_line, ascii_lines, modbus_reply, nmea_lines, registers
from modd_model import parse_text

MODEL = """
Drone d { Sensors {
    Sensor gnss kind nmea on "/g" { clock = instrument; } measures {
        lat("deg", float64) from sentence GGA.lat; lon("deg", float64) from sentence GGA.lon;
        depth(METER) from sentence DBT.depth_meters; p(BAR) from sentence XDR.f6 scale 0.001;
    }
    Sensor ctd kind ascii on "/c" { separator = ";"; } measures {
        t(DEGREE_CELSIUS) from column 2; c("mS/cm") from key "C" scale 0.1;
    }
    Sensor sonde kind modbus on "/s" measures {
        ph(NONE, float64) from register 4 float32 order little;
        o2(NONE, float64) from register 6 int16 scale 0.01;
        n(NONE, float64) from register 0 uint32 unit 3 table input;
    }
} }
PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c");
Publishers { Publisher p(1, "d.gnss.lat", "d.gnss.lon", "d.gnss.depth", "d.gnss.p", "d.ctd.t",
                         "d.ctd.c", "d.sonde.ph", "d.sonde.o2", "d.sonde.n"); }
"""


def _plan(name: str) -> SensorPlan:
    doc, _ = parse_text(MODEL)
    return next(p for p in plan_sensors(doc) if p.name == name)


@given(st.floats(-89, 89), st.floats(-179, 179), st.floats(0, 500), st.floats(0, 2000))
def test_nmea_round_trip(lat: float, lon: float, depth: float, pressure: float) -> None:
    plan = _plan("gnss")
    values = {"d.gnss.lat": lat, "d.gnss.lon": lon, "d.gnss.depth": depth, "d.gnss.p": pressure}
    lines = nmea_lines(plan, values, 1_790_000_000.25)
    for line in lines:
        pynmea2.parse(line, check=True)  # an independent parser accepts every sentence
    health = Health()
    got = LineDecoder(plan, health).feed("".join(x + "\r\n" for x in lines).encode(), 0)
    assert health.lines_bad == 0 and lines[0].startswith("$GPZDA,")
    out = {m.topic: v for m, _, v in got}
    assert out["d.gnss.lat"] == pytest.approx(lat, abs=1e-6)  # 4 decimals of minutes
    assert out["d.gnss.lon"] == pytest.approx(lon, abs=1e-6)
    assert out["d.gnss.depth"] == pytest.approx(depth, abs=1e-4)
    assert out["d.gnss.p"] == pytest.approx(pressure, abs=1e-6)


def test_instrument_time_from_the_simulated_zda() -> None:
    plan = _plan("gnss")
    dec = LineDecoder(plan, Health())
    lines = nmea_lines(plan, {"d.gnss.depth": 3.0}, 1_790_000_000.25)
    computer = 1_790_000_001 * 10**9  # dates are resolved against the computer's clock
    got = dec.feed("".join(x + "\r\n" for x in lines).encode(), computer)
    assert got[0][1] == 1_790_000_000_250_000_000


def test_ascii_round_trip() -> None:
    plan = _plan("ctd")
    line = ascii_line(plan, {"d.ctd.t": 12.5, "d.ctd.c": 45.1})
    assert line == "0;12.5000;C=451.0000"
    got = LineDecoder(plan, Health()).feed(line.encode() + plan.line_end, 0)
    assert {m.topic: v for m, _, v in got} == {"d.ctd.t": 12.5, "d.ctd.c": pytest.approx(45.1)}


def test_modbus_replies_read_back() -> None:
    plan = _plan("sonde")
    regs = registers(plan, {"d.sonde.ph": 7.25, "d.sonde.o2": 8.12, "d.sonde.n": 70000})
    out = {}
    for block in blocks(plan):
        reply = modbus_reply(block.request(), regs)
        assert reply is not None
        words = modbus.parse_reply(reply, block.unit, block.function, block.count)
        out.update({m.topic: v for m, _, v in block_samples(block, words, 0)})
    assert out == {"d.sonde.ph": 7.25, "d.sonde.o2": pytest.approx(8.12), "d.sonde.n": 70000}
    unknown = modbus_reply(modbus.read_request(1, modbus.HOLDING, 900, 1), regs)
    assert unknown is not None
    with pytest.raises(modbus.ExceptionReply):
        modbus.parse_reply(unknown, 1, modbus.HOLDING, 1)
    assert modbus_reply(b"\x01\x03\x00\x00\x00\x01\x00\x00", regs) is None  # bad CRC


CONDITIONS = """
Drone d { Sensors {
    Sensor wx kind nmea on "/w" measures {
        t(NONE) from sentence MWV.angle where reference = T;
        r(NONE) from sentence MWV.angle where reference = R;
        air(NONE) from sentence XDR.value where id = AIRTEMP;
        baro(NONE) from sentence XDR.value where id = BARO;
    }
    Sensor ctd kind ascii on "/c" measures {
        s(NONE) from column 2 where column 1 = S; b(NONE) from column 2 where column 1 = B;
    }
} }
PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c");
Publishers { Publisher p(1, "d.wx.t", "d.wx.r", "d.wx.air", "d.wx.baro", "d.ctd.s", "d.ctd.b"); }
"""


def test_the_simulator_meets_the_models_conditions() -> None:
    doc, _ = parse_text(CONDITIONS)
    wx, ctd = plan_sensors(doc)
    values = {"d.wx.t": 101.5, "d.wx.r": 42.25, "d.wx.air": 12.5, "d.wx.baro": 1.013}
    lines = nmea_lines(wx, values, 1_790_000_000.25)
    assert [pynmea2.parse(x, check=True).sentence_type for x in lines] == ["MWV", "MWV", "XDR"]
    got = LineDecoder(wx, Health()).feed("".join(x + "\r\n" for x in lines).encode(), 0)
    assert {m.topic: v for m, _, v in got} == pytest.approx(values)
    text = "".join(x + "\r\n" for x in ascii_lines(ctd, {"d.ctd.s": 9.5, "d.ctd.b": 12.25}))
    got = LineDecoder(ctd, Health()).feed(text.encode(), 0)
    assert {m.topic: v for m, _, v in got} == {"d.ctd.s": 9.5, "d.ctd.b": 12.25}
