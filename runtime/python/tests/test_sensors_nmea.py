"""The NMEA 0183 parser of modd-sensors against pynmea2, an independent
parser: the same sentences give the same numbers, and the lines pynmea2
refuses for their checksum are refused here too."""

from __future__ import annotations

import contextlib
import datetime

import pynmea2  # type: ignore[import-untyped]
import pytest
from hypothesis import given
from hypothesis import strategies as st
from modd.sensors import nmea
from modd.sensors.validity import no_fix
from modd_model.vocabulary import NMEA_SENTENCES

TALKERS = ["GP", "GN", "GL", "GA", "II", "SD"]


def _ddmm(x: float, width: int) -> str:
    """Degrees and minutes to 1e-4 minute, rounded as a whole (never '60.0000' minutes)."""
    deg, tenths = divmod(round(abs(x) * 600_000), 600_000)
    return f"{deg:0{width}d}{tenths // 10_000:02d}.{tenths % 10_000:04d}"


def _gga(talker: str, lat: float, lon: float, alt: float) -> str:
    """A GGA built by pynmea2 (it computes the checksum) from decimal degrees."""
    fields = (
        "123519.00",
        _ddmm(lat, 2),
        "N" if lat >= 0 else "S",
        _ddmm(lon, 3),
        "E" if lon >= 0 else "W",
        "1",
        "08",
        "0.9",
        f"{alt:.1f}",
        "M",
        "46.9",
        "M",
        "",
        "",
    )
    return str(pynmea2.GGA(talker, "GGA", fields))


@given(
    st.sampled_from(TALKERS),
    st.floats(-89.999, 89.999),
    st.floats(-179.999, 179.999),
    st.floats(-100, 5000),
)
def test_gga_matches_pynmea2(talker: str, lat: float, lon: float, alt: float) -> None:
    line = _gga(talker, lat, lon, alt)
    oracle = pynmea2.parse(line, check=True)
    s = nmea.parse_sentence(line)
    assert (s.talker, s.type) == (talker, "GGA")
    assert nmea.field_value(s, "lat") == pytest.approx(oracle.latitude, abs=1e-12)
    assert nmea.field_value(s, "lon") == pytest.approx(oracle.longitude, abs=1e-12)
    assert nmea.field_value(s, "altitude") == pytest.approx(float(oracle.altitude))
    assert nmea.field_value(s, "satellites") == int(oracle.num_sats)


@given(st.sampled_from(TALKERS), st.floats(0, 2000, allow_nan=False))
def test_depth_and_temperature_match_pynmea2(talker: str, depth: float) -> None:
    dbt = str(
        pynmea2.DBT(
            talker,
            "DBT",
            (f"{depth * 3.28084:.1f}", "f", f"{depth:.2f}", "M", f"{depth * 0.546807:.2f}", "F"),
        )
    )
    mtw = str(pynmea2.MTW(talker, "MTW", (f"{depth / 100:.2f}", "C")))
    assert nmea.field_value(nmea.parse_sentence(dbt), "depth_meters") == float(
        pynmea2.parse(dbt, check=True).depth_meters
    )
    assert nmea.field_value(nmea.parse_sentence(mtw), "temperature") == float(
        pynmea2.parse(mtw, check=True).temperature
    )


@given(
    st.datetimes(min_value=datetime.datetime(2000, 1, 1), max_value=datetime.datetime(2068, 12, 31))
)
def test_instrument_time_matches_pynmea2(when: datetime.datetime) -> None:
    """RMC's two-digit year is 20yy here; pynmea2 (strptime) agrees up to 2068."""
    when = when.replace(microsecond=when.microsecond // 10_000 * 10_000)
    hms = when.strftime("%H%M%S") + f".{when.microsecond // 10_000:02d}"
    zda = str(
        pynmea2.ZDA(
            "GP", "ZDA", (hms, f"{when.day:02d}", f"{when.month:02d}", str(when.year), "00", "00")
        )
    )
    rmc = str(
        pynmea2.RMC(
            "GN",
            "RMC",
            (
                hms,
                "A",
                "4807.038",
                "N",
                "01131.000",
                "E",
                "0.5",
                "84.4",
                when.strftime("%d%m%y"),
                "",
                "",
                "A",
            ),
        )
    )
    for line in (zda, rmc):
        expected = pynmea2.parse(line, check=True).datetime.timestamp()
        stamp = nmea.instrument_time_ns(nmea.parse_sentence(line))
        assert stamp is not None
        assert stamp / 1e9 == pytest.approx(expected, abs=1e-6)


GOOD = "$GPDBT,12.3,f,3.75,M,2.05,F*30"


@pytest.mark.parametrize(
    "line",
    [
        GOOD[:-1] + "D",  # bad checksum
        GOOD[:20],  # truncated: no checksum
        GOOD[:20] + "$GPMTW,12.5,C*02",  # the end of one line glued to the next
        "$GPXDR,C,12.5,C,T1,P*00",  # XDR not in groups of 4 (checksum fixed below)
        "$GP GGA,1*00",  # an address that is not talker + type
    ],
)
def test_bad_lines_are_refused(line: str) -> None:
    if line.endswith("*00"):  # a right checksum: only the form is wrong
        body = line[1 : line.index("*")]
        line = f"${body}*{nmea.checksum(body):02X}"
    with pytest.raises(nmea.BadSentence):
        nmea.parse_sentence(line)


def test_checksum_agrees_with_pynmea2() -> None:
    bad = GOOD[:-1] + "D"
    with pytest.raises(pynmea2.ChecksumError):
        pynmea2.parse(bad, check=True)
    with pytest.raises(nmea.BadSentence, match="bad checksum"):
        nmea.parse_sentence(bad)
    assert nmea.parse_sentence(GOOD).fields[2] == "3.75"


@given(st.binary(max_size=200))
def test_garbage_never_raises_anything_else(data: bytes) -> None:
    line = data.decode("latin-1")
    try:
        s = nmea.parse_sentence(line)
    except nmea.BadSentence:
        return
    for field in NMEA_SENTENCES.get(s.type, {}):
        with contextlib.suppress(nmea.NoValue):
            nmea.field_value(s, field)


def test_void_fix_and_empty_fields_give_no_value() -> None:
    body = "GPRMC,123519,V,,,,,,,230394,,,N"
    s = nmea.parse_sentence(f"${body}*{nmea.checksum(body):02X}")
    assert no_fix(s) == "RMC status V (void)"
    with pytest.raises(nmea.NoValue):
        nmea.field_value(s, "lat")
