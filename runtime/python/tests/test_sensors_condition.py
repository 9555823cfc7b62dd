"""A source's condition (``where``) in modd-sensors' logic apart from I/O: MWV
true and relative wind into two topics, XDR quadruplets picked by transducer
name, a CTD line's record type; sentences and lines that meet no condition
are counted ignored, never bad nor missing. Sentences are written by pynmea2."""

from __future__ import annotations

from typing import Any

import pynmea2  # type: ignore[import-untyped]
import pytest
from modd.sensors.condition import Condition, compare, nmea_field
from modd.sensors.decode import LineDecoder
from modd.sensors.health import Health
from modd.sensors.nmea import parse_sentence
from modd.sensors.plan import SensorPlan, plan_sensors
from modd_model import parse_text

MODEL = r"""
Drone usv { Sensors {
    Sensor wind kind nmea on "/dev/wind" measures {
        true_angle("deg") from sentence MWV.angle where reference = T;
        true_speed("kt") from sentence MWV.speed where reference = T;
        apparent_angle("deg") from sentence MWV.angle where reference = R;
        air_temperature(DEGREE_CELSIUS) from sentence XDR.value where id = AIRTEMP;
        pressure(BAR) from sentence XDR.value where id = "BARO";
        strong("kt") from sentence MWV.speed where speed > 10;
    }
    Sensor ctd kind ascii on "/dev/ctd" measures {
        temperature(DEGREE_CELSIUS) from column 2 where column 1 = S;
        pressure("dbar") from column 3 where column 1 = S;
        battery(V) from column 2 where column 1 = B;
    }
} }
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers {
    Publisher p(0.1, "usv.wind.true_angle", "usv.wind.true_speed", "usv.wind.apparent_angle",
                "usv.wind.air_temperature", "usv.wind.pressure", "usv.wind.strong",
                "usv.ctd.temperature", "usv.ctd.pressure", "usv.ctd.battery");
}
"""


def _plans() -> dict[str, SensorPlan]:
    doc, _ = parse_text(MODEL)
    return {p.name: p for p in plan_sensors(doc)}


def _feed(plan: SensorPlan, lines: list[str]) -> tuple[list[tuple[str, float]], Health]:
    health = Health()
    dec = LineDecoder(plan, health)
    out = dec.feed("".join(line + "\r\n" for line in lines).encode(), 1)
    return [(m.topic.rsplit(".", 1)[1], v) for m, _, v in out], health


def _mwv(angle: float, ref: str, speed: float, status: str = "A") -> str:
    return str(pynmea2.MWV("WI", "MWV", (f"{angle:.1f}", ref, f"{speed:.1f}", "N", status)))


def _xdr(*quads: tuple[str, float, str, str]) -> str:
    fields = [x for t, v, u, n in quads for x in (t, f"{v}", u, n)]
    return str(pynmea2.XDR("II", "XDR", tuple(fields)))


def test_mwv_true_and_relative_wind_go_to_their_own_topics() -> None:
    got, health = _feed(
        _plans()["wind"],
        [_mwv(57.5, "R", 4.2), _mwv(96.6, "T", 12.5), _mwv(73.7, "R", 5.0), _mwv(94.9, "T", 3.0)],
    )
    assert [v for t, v in got if t == "apparent_angle"] == [57.5, 73.7]
    assert [v for t, v in got if t == "true_angle"] == [96.6, 94.9]
    assert [v for t, v in got if t == "true_speed"] == [12.5, 3.0]
    assert [v for t, v in got if t == "strong"] == [12.5]  # a number compared as a number
    assert (health.lines_ok, health.lines_bad, health.ignored, health.missing) == (4, 0, 0, 0)


def test_a_void_mwv_gives_nothing_to_the_topics_it_would_feed() -> None:
    got, health = _feed(_plans()["wind"], [_mwv(57.5, "T", 4.2, "V")])
    assert got == [] and health.missing == 2 and health.no_fix == 2  # true_angle, true_speed


def test_xdr_quadruplet_picked_by_transducer_name() -> None:
    lines = [
        _xdr(("C", 12.5, "C", "AIRTEMP"), ("P", 1.013, "B", "BARO")),
        _xdr(("P", 1.012, "B", "BARO"), ("H", 55.0, "P", "HUMIDITY"), ("C", 12.75, "C", "AIRTEMP")),
        _xdr(("H", 56.0, "P", "HUMIDITY")),
    ]
    got, health = _feed(_plans()["wind"], lines)
    assert [v for t, v in got if t == "air_temperature"] == [12.5, 12.75]
    assert [v for t, v in got if t == "pressure"] == [1.013, 1.012]
    assert health.ignored == 1 and health.missing == 0  # the humidity-only XDR


def test_ctd_record_types() -> None:
    got, health = _feed(_plans()["ctd"], ["S,12.5,3.25", "B,12.1", "S,12.6,3.5", "X,1,2,3"])
    assert got == [
        ("temperature", 12.5),
        ("pressure", 3.25),
        ("battery", 12.1),
        ("temperature", 12.6),
        ("pressure", 3.5),
    ]
    assert (health.lines_ok, health.ignored, health.lines_bad) == (4, 1, 0)
    got, health = _feed(_plans()["ctd"], ["S,12.5"])  # a cut S record: bad, nothing taken
    assert got == [] and health.lines_bad == 1


@pytest.mark.parametrize(
    ("text", "op", "value", "numeric", "holds"),
    [
        ("T", "=", "T", False, True),
        ("T", "!=", "T", False, False),
        ("4.0", "=", "4", True, True),
        ("4.0", "=", "4", False, False),
        ("12", ">=", "12", True, True),
        ("x", ">", "1", True, False),
        ("nan", "!=", "1", True, False),
    ],
)
def test_compare(text: str, op: str, value: str, numeric: bool, holds: bool) -> None:
    assert compare(text, op, value, numeric) is holds


def test_an_empty_field_meets_no_condition() -> None:
    s = parse_sentence(_mwv(57.5, "T", 4.2).replace(",T,", ",,").rsplit("*", 1)[0], False)
    assert nmea_field(s, "angle", Condition("reference", "!=", "R")) is None


def test_conditions_round_trip_in_the_plan() -> None:
    plan: Any = _plans()["wind"]
    assert plan.mappings[0].condition == Condition("reference", "=", "T")
    assert plan.mappings[4].condition == Condition("id", "=", "BARO")
