"""Units, standard names and the platform position in the model: UDUNITS-2
(through cf-units, which bundles the library) is the oracle for units, the
CF standard-name table for names."""

from __future__ import annotations

import argparse
from typing import Any

import cf_units
import pytest
from modd_model import dumps, load_text
from modd_model.collector import print_collector
from modd_model.commands import run_validate
from modd_model.position import platform_position
from modd_model.standard_names import canonical_units, table_version
from modd_model.units import PAPER_UNITS, udunits, unit_problem
from modd_model.vocabulary import KNOWN_UNITS

BASE = """
Drone usv {
    Sensors {
        Sensor ctd measures {
            temp(UNIT) ATTRS;
        }
        Sensor gps measures { lat(degree_north, float64); lon(degree_east, float64); }
    }
    POSITION
}
PubBroker("127.0.0.1":7171, "/l"); SubBroker("127.0.0.1":7272, "/c");
Publishers { Publisher p(1, "usv.ctd.temp", "usv.gps.lat", "usv.gps.lon"); }
Subscriptions { }
"""
POSITION = 'Position { latitude = "usv.gps.lat"; longitude = "usv.gps.lon"; maxGap = 4; }'


def _load(unit: str = "degC", attrs: str = "", position: str = POSITION) -> Any:
    return load_text(
        BASE.replace("UNIT", unit).replace("ATTRS", attrs).replace("POSITION", position), "m.modd"
    )


def test_every_paper_unit_is_its_udunits_equivalent() -> None:
    expected = {
        "METER": "m",
        "METER_PER_SECOND": "m/s",
        "METER_PER_SECOND_SQUARED": "m/s2",
        "DEGREE_CELSIUS": "Celsius",
        "RADIAN": "radian",
        "RADIAN_PER_SECOND": "radian/s",
        "BAR": "100 kPa",
        "LITER": "dm3",
        "GRAM": "kg/1000",
        "NONE": "1",
    }
    assert set(PAPER_UNITS) == set(KNOWN_UNITS) == set(expected)
    for name, same in expected.items():
        ours = cf_units.Unit(udunits(name))
        assert ours == cf_units.Unit(same), name  # UDUNITS says they are one unit
        assert _load(name).ok, name


@pytest.mark.parametrize(
    "typed,same",
    [
        ("m/s²", "m s-2"),
        ("°C", "degC"),
        ("µS/cm", "uS cm-1"),
        ("kg·m⁻³", "kg m-3"),
        ("PSU", "1"),
        ("deg", "degree"),
    ],
)
def test_typed_symbols_are_read_as_udunits(typed: str, same: str) -> None:
    text = udunits(typed)
    assert text.isascii()
    assert cf_units.Unit(text) == cf_units.Unit(same)
    assert _load(f'"{typed}"').ok


def test_a_unit_udunits_does_not_know_is_a_located_error() -> None:
    result = _load('"bananas per hour"')
    (err,) = result.errors
    assert "'bananas per hour' is not a UDUNITS-2 unit" in err.message
    assert err.pointer == "/drone/sensors/0/variables/0/unit"
    assert err.location is not None and (err.location.line, err.location.col) == (5, 18)
    assert unit_problem("m s-2") is None


def test_standard_names_come_from_the_shipped_cf_table() -> None:
    assert table_version().startswith("CF standard name table version 93")
    assert canonical_units("sea_water_temperature") == "K"
    ok = _load(
        attrs='{ standardName = sea_water_temperature; longName = "T"; validMin = -2; '
        "validMax = 40; }"
    )
    assert ok.ok, [str(d) for d in ok.diagnostics]
    var = ok.model["drone"]["sensors"][0]["variables"][0]
    assert var == {
        "name": "temp",
        "unit": "degC",
        "standardName": "sea_water_temperature",
        "longName": "T",
        "validMin": -2.0,
        "validMax": 40.0,
    }
    wrong_unit = _load("METER", "{ standardName = sea_water_temperature; }")
    assert [e.message for e in wrong_unit.errors] == [
        "unit 'METER' does not convert to 'K', the unit of the standard name "
        "'sea_water_temperature'"
    ]
    unknown = _load(attrs="{ standardName = water_warmth; }")
    assert unknown.errors[0].pointer == "/drone/sensors/0/variables/0/standardName"
    reversed_range = _load(attrs="{ validMin = 5; validMax = 1; }")
    assert "validMin 5 is above validMax 1" in reversed_range.errors[0].message


def test_attributes_and_position_round_trip_through_text_and_json() -> None:
    result = _load(attrs='{ standardName = sea_water_temperature; longName = "Temp \\"C\\""; }')
    assert result.ok
    for fmt in ("modd", "json"):
        again = load_text(dumps(result.model, fmt), f"again.{fmt}", fmt)
        assert again.ok and again.model == result.model, fmt
    assert result.model["drone"]["position"] == {
        "latitude": "usv.gps.lat",
        "longitude": "usv.gps.lon",
        "maxGapS": "4.0",
    }


def test_the_collector_form_leaves_the_new_parts_out_and_says_so() -> None:
    model = _load('"m s-1"', '{ longName = "speed"; }').model
    text, omitted = print_collector(model)
    pointers = {d.pointer for d in omitted}
    assert {"/drone/position", "/drone/sensors/0/variables/0/longName"} <= pointers
    assert "temp(METER_PER_SECOND)" in text  # the UDUNITS spelling of one of the paper's units
    model["drone"]["sensors"][0]["variables"][0]["unit"] = "km/h"
    assert "temp(NONE)" in print_collector(model)[0]  # none of the paper's units
    # written as the UDUNITS spelling of one, it goes back to the paper's name
    model["drone"]["sensors"][0]["variables"][0]["unit"] = PAPER_UNITS["METER_PER_SECOND_SQUARED"]
    assert "temp(METER_PER_SECOND_SQUARED)" in print_collector(model)[0]


def test_the_position_is_checked_and_defaults_to_the_autopilot() -> None:
    bad = _load(position='Position { latitude = "usv.ctd.temp"; longitude = "usv.gps.nope"; }')
    messages = {e.pointer: e.message for e in bad.errors}
    assert "does not convert to 'degree_north'" in messages["/drone/position/latitude"]
    assert messages["/drone/position/longitude"] == "unknown topic 'usv.gps.nope'"
    none = _load(position="")
    assert none.ok and none.model is not None and platform_position(none.model) is None
    auto = load_text(
        BASE.replace("UNIT", "degC")
        .replace("ATTRS", "")
        .replace("POSITION", "")
        .replace(
            "Sensor gps measures { lat(degree_north, float64); lon(degree_east, float64); }",
            "Sensor gps kind mavlink measures { lat(degree_north, float64) "
            "from GLOBAL_POSITION_INT.lat scale 1e-7; lon(degree_east, float64)"
            " from GLOBAL_POSITION_INT.lon scale 1e-7; }",
        ),
        "auto.modd",
    )
    assert auto.model is not None
    pos = platform_position(auto.model)
    assert pos is not None and (pos.latitude, pos.longitude, pos.declared) == (
        "usv.gps.lat",
        "usv.gps.lon",
        False,
    )


def test_validate_says_when_a_dataset_would_have_no_position(
    tmp_path: Any, capsys: pytest.CaptureFixture[str]
) -> None:
    path = tmp_path / "m.modd"
    path.write_text(BASE.replace("UNIT", "degC").replace("ATTRS", "").replace("POSITION", ""))
    args = argparse.Namespace(files=[str(path)], encoding=None, quiet=False)
    assert run_validate(args) == 0
    err = capsys.readouterr().err
    assert "warning: no platform position: datasets (modd dataset) will have no latitude" in err
    path.write_text(BASE.replace("UNIT", "degC").replace("ATTRS", "").replace("POSITION", POSITION))
    assert run_validate(args) == 0
    assert "no platform position" not in capsys.readouterr().err
