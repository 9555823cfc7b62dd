"""Instrument sensors (kind nmea, ascii, modbus) in the text form and the
validator: they round-trip through print → parse, and each mistake an
integrator makes is reported at its place (JSON pointer and line:col)."""

from __future__ import annotations

import string
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from modd_model import parse_text, print_model
from modd_model.parser import parse_lenient
from modd_model.validate import validate
from modd_model.vocabulary import NMEA_SENTENCES

BROKERS = 'PubBroker("127.0.0.1":1, "/l"); SubBroker("127.0.0.1":2, "/c");'
SENSORS = r"""
Sensor gnss "u-blox" kind nmea on "/dev/serial/by-id/usb-u-blox" {
    baud = 9600; clock = instrument; checksum = optional; fix = rtk;
} measures {
    lat("deg", float64) from sentence GGA.lat;
    sats(NONE, int) from sentence GGA.satellites;
    depth(METER) from sentence DBT.f3 scale 1.0 offset -0.5;
    wind_true("deg") from sentence MWV.angle where reference = T;
    air(DEGREE_CELSIUS) from sentence XDR.value where id != "AIR TEMP";
    rtk_lat("deg", float64) from sentence GGA.lat where quality >= 4;
}
Sensor ctd kind ascii on "/dev/ttyUSB1" {
    separator = " "; terminator = lf; start = "START"; pattern = "T=(?P<T>\\S+) C=(\\S+)";
} measures {
    t(DEGREE_CELSIUS) from key T;
    c("mS/cm") from column 2 scale 0.1;
    s(NONE) from column 2 where column 1 = "S";
}
Sensor sonde kind modbus on "/dev/ttyUSB2" { baud = 19200; parity = even; stop = 2; } measures {
    ph(NONE) from register 100 float32 unit 2 table input order little;
    o2(NONE) from register 7 int16 scale 0.01;
}
"""


def _model(sensors: str, publishers: str = "") -> str:
    return f"Drone d {{ Sensors {{ {sensors} }} }} {BROKERS} Publishers {{ {publishers} }}"


def test_instrument_sensors_round_trip() -> None:
    doc, _ = parse_text(_model(SENSORS))
    gnss, ctd, sonde = doc["drone"]["sensors"]
    assert gnss["device"] == {"path": "/dev/serial/by-id/usb-u-blox", "baud": 9600}
    assert (gnss["clock"], gnss["checksum"], gnss["fix"]) == ("instrument", "optional", "rtk")
    assert gnss["variables"][2]["nmea"] == {
        "sentence": "DBT",
        "field": "f3",
        "scale": 1.0,
        "offset": -0.5,
    }
    assert ctd["line"] == {
        "separator": " ",
        "terminator": "lf",
        "startCommand": "START",
        "pattern": r"T=(?P<T>\S+) C=(\S+)",
    }
    assert gnss["variables"][3]["nmea"]["where"] == {"field": "reference", "op": "=", "value": "T"}
    assert gnss["variables"][4]["nmea"]["where"] == {"field": "id", "op": "!=", "value": "AIR TEMP"}
    assert gnss["variables"][5]["nmea"]["where"] == {"field": "quality", "op": ">=", "value": "4"}
    assert ctd["variables"][0]["ascii"] == {"key": "T"}
    assert ctd["variables"][2]["ascii"]["where"] == {"column": 1, "op": "=", "value": "S"}
    assert sonde["device"]["parity"] == "even" and sonde["device"]["stopBits"] == 2
    assert sonde["variables"][0]["modbus"] == {
        "unit": 2,
        "register": 100,
        "table": "input",
        "type": "float32",
        "wordOrder": "little",
    }
    text = print_model(doc)
    again, _ = parse_text(text)
    assert again == doc
    assert print_model(again) == text
    assert [d for d in validate(doc) if d.severity == "error"] == []


def _errors(sensors: str) -> dict[str, tuple[str, int]]:
    """pointer -> (message, line) of every error of a model with these sensors."""
    doc, smap, diagnostics = parse_lenient(_model(sensors))
    assert doc is not None and diagnostics == []
    out = {}
    for d in validate(doc):
        if d.severity == "error":
            loc = smap.get(d.pointer)
            out[d.pointer] = (d.message, loc.line if loc else 0)
    return out


@pytest.mark.parametrize(
    ("sensor", "pointer", "words"),
    [
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence ABC.f1; }',
            "/drone/sensors/0/variables/0/nmea/field",
            "unknown NMEA sentence 'ABC'",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence DBT.f7; }',
            "/drone/sensors/0/variables/0/nmea/field",
            "DBT has 6 fields: f7 is out of range",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence GGA.time; }',
            "/drone/sensors/0/variables/0/nmea/field",
            "GGA.time holds time, not a number",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence GGA.height; }',
            "/drone/sensors/0/variables/0/nmea/field",
            "GGA has no field 'height'",
        ),
        (
            "Sensor g kind nmea measures { x(NONE) from sentence GGA.lat; }",
            "/drone/sensors/0",
            "needs its serial device",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE); }',
            "/drone/sensors/0/variables/0",
            "needs a source: from sentence SENTENCE.field",
        ),
        (
            'Sensor g on "/d" measures { x(NONE); }',
            "/drone/sensors/0/device",
            "device is only for a sensor of kind nmea or ascii or modbus",
        ),
        (
            'Sensor g kind ascii on "/d" { clock = instrument; } '
            "measures { x(NONE) from column 1; }",
            "/drone/sensors/0/clock",
            "clock is only for a sensor of kind nmea",
        ),
        (
            'Sensor g kind modbus on "/d" { fix = rtk; checksum = optional; } '
            "measures { x(NONE) from register 1 int16; }",
            "/drone/sensors/0/fix",
            "fix is only for a sensor of kind nmea",
        ),
        (
            'Sensor g kind ascii on "/d" measures { x(NONE) from register 1 int16; }',
            "/drone/sensors/0/variables/0/modbus",
            "is read as modbus but sensor 'g' is of kind ascii",
        ),
        (
            'Sensor g kind ascii on "/d" { pattern = "(a"; } measures { x(NONE) from column 1; }',
            "/drone/sensors/0/line/pattern",
            "not a regular expression",
        ),
        (
            'Sensor g kind ascii on "/d" { pattern = "(?P<a>.*)"; } '
            "measures { x(NONE) from key b; }",
            "/drone/sensors/0/variables/0/ascii/key",
            "no group named 'b'",
        ),
        (
            'Sensor g kind modbus on "/d" measures { a(NONE) from register 10 float32; '
            "b(NONE) from register 11 uint16; }",
            "/drone/sensors/0/variables/1/modbus/register",
            "register 11 of unit 1 (holding) is read by 'a' as a float32 at 10",
        ),
        (
            'Sensor g kind modbus on "/d" measures { a(NONE) from register 10 int32; '
            "b(NONE) from register 10 int32 order little; }",
            "/drone/sensors/0/variables/1/modbus/register",
            "(big word order) and here as a int32",
        ),
        (
            'Sensor g kind modbus on "/d" measures { a(NONE) from register 65535 float32; }',
            "/drone/sensors/0/variables/0/modbus/register",
            "runs past register 65535",
        ),
        (
            'Sensor g kind modbus on "/d" measures { a(NONE) from register 1 int16 scale 0; }',
            "/drone/sensors/0/variables/0/modbus/scale",
            "scale must be a finite number",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence MWV.angle '
            "where refrence = T; }",
            "/drone/sensors/0/variables/0/nmea/where/field",
            "where: MWV has no field 'refrence'",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence MWV.angle '
            "where reference < T; }",
            "/drone/sensors/0/variables/0/nmea/where/op",
            "MWV.reference holds text: compare it with = or !=, not <",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence GGA.lat '
            "where quality >= T; }",
            "/drone/sensors/0/variables/0/nmea/where/value",
            "GGA.quality holds a number: compare it with a number, not 'T'",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence GGA.lat where time = 3; }',
            "/drone/sensors/0/variables/0/nmea/where/field",
            "GGA.time holds a time; a condition compares text or numbers",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence XDR.f2 where id = A; }',
            "/drone/sensors/0/variables/0/nmea/field",
            "id picks an XDR quadruplet: read the quadruplet's field",
        ),
        (
            'Sensor g kind ascii on "/d" measures { x(NONE) from column 2 where column 1 > S; }',
            "/drone/sensors/0/variables/0/ascii/where/value",
            "> compares numbers: 'S' is not a number",
        ),
        (
            'Sensor g kind ascii on "/d" { pattern = "(?P<a>.*)"; } '
            "measures { x(NONE) from key a where key b = S; }",
            "/drone/sensors/0/variables/0/ascii/where/key",
            "no group named 'b'",
        ),
        (
            'Sensor g kind nmea on "/d" measures { x(NONE) from sentence MWV.angle '
            'where reference = "a,b"; }',
            "/drone/sensors/0/variables/0/nmea/where/value",
            "'a,b' is not well-formed",
        ),
    ],
)
def test_mistakes_are_located(sensor: str, pointer: str, words: str) -> None:
    errors = _errors(sensor)
    assert pointer in errors, errors
    message, line = errors[pointer]
    assert words in message
    assert line == 1


def test_an_unknown_fix_class_is_located() -> None:
    doc, smap, diagnostics = parse_lenient(
        _model(
            'Sensor g kind nmea on "/d" {\n fix = survey; } measures { '
            "x(NONE) from sentence GGA.lat; }"
        )
    )
    assert doc is not None and diagnostics == []
    (err,) = [d for d in validate(doc) if d.pointer == "/drone/sensors/0/fix"]
    assert "rtkFixed" in err.message or "survey" in err.message
    loc = smap["/drone/sensors/0/fix"]
    assert loc.line == 2


def test_same_register_read_alike_is_fine() -> None:
    """Two topics from one register (raw and scaled) and different units do not clash."""
    assert (
        _errors(
            'Sensor g kind modbus on "/d" measures { a(NONE) from register 10 float32; '
            "b(NONE) from register 10 float32 scale 2; "
            "c(NONE) from register 10 uint16 unit 2; }"
        )
        == {}
    )


def test_talker_is_not_part_of_the_sentence() -> None:
    """The sentence names the type only: GPGGA is refused, with the known types listed."""
    errors = _errors('Sensor g kind nmea on "/d" measures { x(NONE) from sentence GPGGA.f1; }')
    message, _ = errors["/drone/sensors/0/variables/0/nmea/sentence"]
    assert "'GPGGA' is not one of" in message


def test_schema_refuses_bad_device_settings() -> None:
    doc: dict[str, Any]
    doc, _ = parse_text(
        _model(
            'Sensor g kind nmea on "/d" { parity = mark; baud = 7; } '
            "measures { x(NONE) from sentence GGA.lat; }"
        )
    )
    pointers = {d.pointer for d in validate(doc) if d.severity == "error"}
    assert {"/drone/sensors/0/device/parity", "/drone/sensors/0/device/baud"} <= pointers


# -- any instrument sensor round-trips (print -> parse -> the same document) ------------

_names = st.from_regex(r"[a-z_][a-z0-9_]{0,8}", fullmatch=True)
_finite = st.floats(allow_nan=False, allow_infinity=False)
_factors = {"scale": _finite, "offset": _finite}
_text = st.text(
    alphabet=string.printable.replace("\x0b", "").replace("\x0c", ""), min_size=1, max_size=12
)
_ops = st.sampled_from(["=", "!=", "<", "<=", ">", ">="])
_values = st.one_of(_text, st.from_regex(r"[+-]?[0-9]{1,4}(\.[0-9]{0,3})?", fullmatch=True))
_nmea_where = st.fixed_dictionaries({"field": _names, "op": _ops, "value": _values})
_ascii_where = st.one_of(
    st.fixed_dictionaries({"column": st.integers(1, 256), "op": _ops, "value": _values}),
    st.fixed_dictionaries({"key": _text, "op": _ops, "value": _values}),
)
_sources: st.SearchStrategy[dict[str, Any]] = st.one_of(
    st.fixed_dictionaries(
        {
            "nmea": st.fixed_dictionaries(
                {"sentence": st.sampled_from(list(NMEA_SENTENCES)), "field": _names},
                optional={**_factors, "where": _nmea_where},
            )
        }
    ),
    st.fixed_dictionaries(
        {
            "ascii": st.one_of(
                st.fixed_dictionaries(
                    {"column": st.integers(1, 256)}, optional={**_factors, "where": _ascii_where}
                ),
                st.fixed_dictionaries({"key": _text}, optional={**_factors, "where": _ascii_where}),
            )
        }
    ),
    st.fixed_dictionaries(
        {
            "modbus": st.fixed_dictionaries(
                {"register": st.integers(0, 65535), "type": st.sampled_from(["int16", "float32"])},
                optional={
                    "unit": st.integers(1, 247),
                    "table": st.sampled_from(["holding", "input"]),
                    "wordOrder": st.sampled_from(["big", "little"]),
                    **_factors,
                },
            )
        }
    ),
    st.just({}),
)
_sensors = st.fixed_dictionaries(
    {
        "name": _names,
        "variables": st.lists(
            st.builds(lambda n, s: {"name": n, "unit": "NONE", **s}, _names, _sources),
            min_size=1,
            max_size=3,
        ),
    },
    optional={
        "kind": st.sampled_from(["generic", "mavlink", "nmea", "ascii", "modbus"]),
        "device": st.fixed_dictionaries(
            {},
            optional={
                "path": _text,
                "baud": st.integers(300, 4_000_000),
                "parity": st.sampled_from(["none", "even", "odd"]),
                "stopBits": st.integers(1, 2),
            },
        ),
        "line": st.fixed_dictionaries(
            {},
            optional={
                "separator": _text,
                "terminator": st.sampled_from(["crlf", "lf", "cr"]),
                "startCommand": _text,
                "pattern": _text,
            },
        ),
        "clock": st.sampled_from(["receive", "instrument"]),
        "checksum": st.sampled_from(["required", "optional"]),
        "fix": st.sampled_from(["gnss", "any", "differential", "rtk", "rtkFixed"]),
    },
)


@settings(max_examples=200, deadline=None)  # timing is not what it checks (shared machines)
@given(st.lists(_sensors, min_size=1, max_size=3))
def test_any_instrument_sensor_round_trips(sensors: list[dict[str, Any]]) -> None:
    for s in sensors:
        if s.get("device") == {}:
            del s["device"]
        if s.get("line") == {}:
            del s["line"]
    doc = {
        "schemaVersion": "1.0",
        "drone": {"name": "d", "sensors": sensors},
        "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 1}, "logPath": "/l"},
        "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 2}, "configPath": "/c"},
        "publishers": [],
        "subscribers": [],
    }
    again, _ = parse_text(print_model(doc))
    assert again == doc
