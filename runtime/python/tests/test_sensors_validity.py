"""Issue 39: NMEA's validity fields decide what is a value (a fix at 0°, 0° is
one), a sensor narrows the fixes it accepts, the instrument clock resolves
dates against the computer's, and sentences of every receiver family are read:
longer ones, vendors' own lines (ignored, not bad), checksum-less ones when the
model says so."""

from __future__ import annotations

import calendar
import dataclasses

import pynmea2  # type: ignore[import-untyped]
import pytest
from modd.sensors import nmea
from modd.sensors.clock import HOLD_MAX, resolve_date
from modd.sensors.decode import LineDecoder
from modd.sensors.health import Health
from modd.sensors.plan import plan_sensors
from modd.sensors.validity import no_fix
from modd_model import parse_text

MODEL = """
Drone usv { Sensors {
    Sensor gnss kind nmea on "/dev/gnss" measures {
        lat("deg", float64) from sentence GGA.lat; rlat("deg", float64) from sentence RMC.lat;
        course("deg") from sentence VTG.course_true; pdop(NONE) from sentence GSA.pdop;
    }
} }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers { Publisher nav(0.1, "usv.gnss.lat", "usv.gnss.rlat", "usv.gnss.course",
                           "usv.gnss.pdop"); }
"""


def line(body: str) -> str:
    return f"${body}*{pynmea2.NMEASentence.checksum(body):02X}"


def decoder(**change: object) -> tuple[LineDecoder, Health]:
    doc, _ = parse_text(MODEL)
    plan = dataclasses.replace(plan_sensors(doc)[0], **change)  # type: ignore[arg-type]
    health = Health()
    return LineDecoder(plan, health), health


def feed(dec: LineDecoder, *bodies: str, now: int = 1) -> dict[str, list[float]]:
    out: dict[str, list[float]] = {}
    data = "".join(line(b) + "\r\n" for b in bodies).encode()
    for m, _, v in dec.feed(data, now):
        out.setdefault(m.topic.rsplit(".", 1)[1], []).append(v)
    return out


GGA = "GPGGA,120000,0000.0000,N,00000.0000,E,{q},08,0.9,5.0,M,0.0,M,,"


@pytest.mark.parametrize(
    ("q", "values"), [("0", 0), ("", 0), ("1", 1), ("4", 1), ("6", 0), ("8", 0)]
)
def test_gga_fix_quality_decides_and_null_island_is_data(q: str, values: int) -> None:
    dec, health = decoder()
    got = feed(dec, GGA.format(q=q))
    assert len(got.get("lat", [])) == values
    assert got.get("lat", [0.0]) == [0.0]  # 0°, 0° with a fix is a value like any other
    assert health.no_fix == 1 - values and health.missing == 1 - values
    if not values:
        assert "GGA fix quality" in health.last_missing


def test_modes_status_and_gsa_fix_type() -> None:
    dec, health = decoder()
    got = feed(
        dec,
        "GPRMC,120000,A,4807.038,N,01131.000,E,0.5,84.4,230394,,,N",  # status A but mode N
        "GPRMC,120001,A,4807.038,N,01131.000,E,0.5,84.4,230394,,,A",
        "GPRMC,120002,A,4807.038,N,01131.000,E,0.5,84.4,230394,,",  # NMEA 2.0: no mode
        "GPVTG,84.4,T,,M,0.5,N,0.9,K,N",
        "GPVTG,84.5,T,,M,0.5,N,0.9,K,A",
        "GPGSA,A,1,,,,,,,,,,,,,99.9,99.9,99.9",
        "GPGSA,A,3,01,02,03,,,,,,,,,,2.5,1.3,2.1,1",  # NMEA 4.11: system id
    )
    assert got == {"rlat": [pytest.approx(48.1173)] * 2, "course": [84.5], "pdop": [2.5]}
    assert health.no_fix == 3 and health.lines_bad == 0


def test_a_sensor_narrowed_to_rtk_fixes() -> None:
    dec, health = decoder(fix="rtk")
    got = feed(
        dec,
        GGA.format(q="1"),
        GGA.format(q="4"),
        GGA.format(q="5"),
        "GPRMC,120002,A,4807.038,N,01131.000,E,0.5,84.4,230394,,",  # states no class: refused
        "GPRMC,120002,A,4807.038,N,01131.000,E,0.5,84.4,230394,,,R",
    )
    assert len(got["lat"]) == 2 and len(got["rlat"]) == 1
    assert health.missing == 2
    assert no_fix(nmea.parse_sentence(line(GGA.format(q="1"))), "rtkFixed") is not None


def test_every_receiver_family_is_read_and_ignored_lines_are_not_bad() -> None:
    dec, health = decoder()
    got = feed(
        dec,
        GGA.format(q="1") + ",",  # BeiDou: one more empty field (15)
        "GNGSA,A,3,01,02,03,04,05,06,07,08,09,10,11,12,1.5,0.9,1.2,1,01,02,03,04,05,06,07,08,09,10",
        "PUBX,00,120000.00,4807.038,N,01131.000,E,545.4,G3,2.1,2.0,0.0,77.52,0.0,,0.92,1.19,0.77,9,0,0",
        "LOG108,1,2,3",
        "PSRFTXT,Version GSW3.2.2",
    )
    assert got["lat"] == [0.0] and got["pdop"] == [1.5]
    assert (health.lines_ok, health.lines_bad, health.ignored) == (5, 0, 3)
    raw = b"$GPGGA,120000,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,\r\n"
    dec.feed(raw, 1)  # no checksum, required: bad
    assert health.lines_bad == 1 and "no *hh checksum" in health.last_bad


def test_checksum_optional_reads_well_formed_lines_only() -> None:
    dec, health = decoder(checksum_required=False)
    good = b"$GPGGA,222449,3349.0337,S,01843.9282,E,1,07,02.31,000115.4,M,0033.3,M,,\r\n"
    cut = b"$GPGGA,222449,3349.0337,S,0184\r\n"  # a cut line: the longitude has no shape
    merged = b"$GPGGA,222449,3349.0337,S,01843.9282,E,1,07$GPZDA,222449,25,10,2010,+00,00\r\n"
    out = dec.feed(good + cut + merged + (line(GGA.format(q="1")) + "\r\n").encode(), 1)
    lats = [v for m, _, v in out if m.topic.endswith(".lat")]
    assert lats == [pytest.approx(pynmea2.parse(good.decode().strip()).latitude), 0.0]
    assert health.lines_bad == 2


def test_dates_resolved_against_the_computer_clock() -> None:
    def ns(y: int, m: int, d: int) -> int:
        return calendar.timegm((y, m, d, 0, 0, 0)) * 10**9

    # the Telit of april6_2019.log: "220899" just after the April 2019 rollover
    assert resolve_date(99, 8, 22, True, ns(2019, 4, 10)) == ns(2019, 4, 7)
    assert resolve_date(99, 8, 22, True, ns(2026, 12, 4)) == ns(2019, 4, 7)
    assert resolve_date(26, 12, 4, True, ns(2026, 12, 4)) == ns(2026, 12, 4)
    assert resolve_date(7, 4, 21, True, ns(2026, 12, 4)) == ns(2026, 12, 5)  # 1024 weeks early
    assert resolve_date(2026, 12, 5, False, ns(2026, 12, 4)) == ns(2026, 12, 5)
    with pytest.raises(ValueError, match="date"):
        resolve_date(26, 2, 31, True, ns(2026, 12, 4))


def test_held_samples_are_bounded_until_a_date() -> None:
    dec, health = decoder(instrument_clock=True)
    for _ in range(HOLD_MAX + 10):
        assert feed(dec, GGA.format(q="1")) == {}
    assert len(dec.held) == HOLD_MAX and health.missing == 10
    assert "no date" in health.last_missing
    day = calendar.timegm((2026, 12, 4, 0, 0, 0)) * 10**9
    released = dec.feed((line("GPZDA,120001,04,12,2026,00,00") + "\r\n").encode(), day)
    assert {s for _, s, _ in released} == {day + 12 * 3600 * 10**9}
