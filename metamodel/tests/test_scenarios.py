"""The paper's scenarios load, validate and round-trip in both notations."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from modd_model import dumps, load_file, load_model, load_text

DATA = Path(__file__).parent / "data"


@pytest.mark.parametrize("name", ["scenario1.modd", "scenario2.modd"])
def test_scenario_is_valid_without_warnings(scenarios_dir: Path, name: str) -> None:
    result = load_file(scenarios_dir / name)
    assert result.ok, [str(d) for d in result.diagnostics]
    assert result.diagnostics == []


@pytest.mark.parametrize("name", ["scenario1.modd", "scenario2.modd"])
def test_scenario_round_trips_through_text_and_json(scenarios_dir: Path, name: str) -> None:
    model = load_model(scenarios_dir / name)
    text = dumps(model, "modd")
    again = load_text(text, "printed.modd")
    assert again.ok and again.model == model
    assert dumps(again.model, "modd") == text  # printing is stable
    from_json = load_text(dumps(model, "json"), "m.json", "json")
    assert from_json.ok and from_json.model == model


def test_scenario1_content(scenarios_dir: Path) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    assert model["drone"]["name"] == "usv"
    assert [v["name"] for v in model["drone"]["sensors"][0]["variables"]] == [
        "accel_x",
        "accel_y",
        "accel_z",
    ]
    assert model["publishers"][0]["periodS"] == "0.04"
    assert [s["periodS"] for s in model["subscribers"]] == ["2.0", "2.0"] + ["0.25"] * 5
    assert model["pubBroker"]["endpoint"] == {"host": "127.0.0.1", "port": 7171}
    assert model["subscribers"][6] == {
        "name": "sub_7",
        "endpoint": {"host": "127.0.0.1", "port": 7407},
        "topic": "usv.accelerometer.accel_z",
        "periodS": "0.25",
        "aggregation": "MAX",
    }


def test_scenario2_has_19_topics_and_subscriptions(scenarios_dir: Path) -> None:
    model = load_model(scenarios_dir / "scenario2.modd")
    assert len(model["drone"]["sensors"][0]["variables"]) == 19
    assert len(model["subscribers"]) == 19
    assert {s["aggregation"] for s in model["subscribers"]} == {"MIN"}


def test_datacollector_form_loads_to_identical_model(scenarios_dir: Path) -> None:
    listing1 = load_model(scenarios_dir / "scenario1.modd")
    wrapped = load_model(DATA / "scenario1_datacollector.modd")
    assert wrapped == listing1


def test_named_brokers_and_missing_semicolons(scenarios_dir: Path) -> None:
    listing1 = load_model(scenarios_dir / "scenario1.modd")
    named = load_model(DATA / "scenario1_named_brokers.modd")
    assert named["pubBroker"].pop("name") == "broker"
    assert named["subBroker"].pop("name") == "base"
    assert named == listing1


def test_json_form_keeps_layout_that_text_drops(scenarios_dir: Path) -> None:
    model = load_model(scenarios_dir / "scenario1.modd")
    model["layout"] = {"nodes": {"sensor:accelerometer": {"x": 10.5, "y": -3}}}
    back = load_text(json.dumps(model), "m.json", "json")
    assert back.ok and back.model == model
    via_text = load_text(dumps(model, "modd"), "m.modd")
    assert via_text.model is not None and "layout" not in via_text.model


def test_product_extensions_round_trip() -> None:
    text = (DATA / "extended.modd").read_text()
    result = load_text(text, "extended.modd")
    assert result.ok, [str(d) for d in result.diagnostics]
    model = result.model
    assert model is not None
    assert model["link"] == {
        "transport": "tcp",
        "keyRef": "env:MODD_PSK",
        "expectedRttS": "0.05",
        "maxBuffer": 500,
        "pingS": "0.5",
        "alpha": "1.0",
        "beta": "2.5",
    }
    assert model["pubBroker"]["ingress"] == {
        "unixSocket": "/tmp/modd/ingress.sock",
        "tcpPort": 7170,
    }
    water = model["drone"]["sensors"][1]["variables"]
    assert water[1] == {
        "name": "conductivity",
        "unit": "mS/cm",
        "type": "float64",
        "description": 'Water conductivity "EC25"',
    }
    assert "endpoint" not in model["subscribers"][1]
    autopilot = model["drone"]["sensors"][2]
    assert autopilot["kind"] == "mavlink"
    assert autopilot["variables"][0]["source"] == {
        "message": "GLOBAL_POSITION_INT",
        "field": "lat",
        "scale": 1e-7,
    }
    assert autopilot["variables"][1]["source"]["offset"] == -0.5
    assert load_text(dumps(model, "modd"), "again.modd").model == model
