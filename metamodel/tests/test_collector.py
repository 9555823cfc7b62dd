"""The original tool's language: its lexical forms and relaxed rules load, its
files in windows-1252 load, and `modd convert --to collector` writes back a
file that loads to the same model (saying what it left out)."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from modd_model import load_model, load_text
from modd_model.collector import ORIGINAL_AGGREGATIONS, print_collector
from modd_model.io import load_file
from modd_model.units import PAPER_UNITS
from modd_model.vocabulary import KNOWN_UNITS

# The random documents of the print/parse property tests, shared.
_spec = importlib.util.spec_from_file_location(
    "roundtrip_strategies", Path(__file__).with_name("test_roundtrip_property.py")
)
assert _spec is not None and _spec.loader is not None
_strategies = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(_strategies)
documents = _strategies.documents

DATA = Path(__file__).parent / "data" / "collector"
MODD = [sys.executable, "-m", "modd_model.cli"]


def _load(path: Path) -> dict[str, Any]:
    result = load_file(path)
    assert result.ok, [str(d) for d in result.diagnostics]
    assert result.model is not None
    return result.model


def test_original_example_loads_with_warnings_not_errors() -> None:
    result = load_file(DATA / "original_example.collector")
    assert result.ok, [str(d) for d in result.errors]
    warnings = {d.pointer: d.message for d in result.diagnostics if d.severity == "warning"}
    # two subscribers on one endpoint, a publisher on the PubBroker's endpoint
    assert "shared with /subscribers/0/endpoint" in warnings["/subscribers/1/endpoint"]
    assert "/pubBroker/endpoint" in warnings["/publishers/0/endpoint"]
    model = result.model
    assert model is not None
    # a publisher and a subscriber may share a name (two name spaces)
    assert model["publishers"][1]["name"] == model["subscribers"][2]["name"] == "thermometer"
    assert model["publishers"][0]["periodS"] == "0.04"
    assert model["subscribers"][2]["periodS"] == "4.0"
    assert model["pubBroker"]["name"] == "broker" and model["subBroker"]["name"] == "base"
    # every warning is located in the file
    for d in result.diagnostics:
        assert d.location is not None and d.location.line > 0, str(d)


def test_every_unit_and_aggregation_of_the_original() -> None:
    m = _load(DATA / "all_words.collector")
    units = [v["unit"] for s in m["drone"]["sensors"] for v in s["variables"]]
    assert sorted(units) == sorted(KNOWN_UNITS)
    assert [s["aggregation"] for s in m["subscribers"]] == list(ORIGINAL_AGGREGATIONS)
    assert [p["periodS"] for p in m["publishers"]] == ["0.1", "1.0"]
    assert m["pubBroker"]["endpoint"] == {"host": "127.0.0.2", "port": 7171}
    assert all("endpoint" in s for s in m["subscribers"])


def test_topic_published_twice_is_a_warning() -> None:
    text = (
        (DATA / "original_example.collector")
        .read_text()
        .replace(
            'Publisher thermometer("127.0.0.1":7373, 1.0, "usv.thermometer.temperature")',
            'Publisher thermometer("127.0.0.1":7373, 1.0, "usv.thermometer.temperature",'
            ' "usv.accelerometer.accel_x")',
        )
    )
    result = load_text(text, "twice.collector")
    assert result.ok
    [w] = [d for d in result.diagnostics if "also published by" in d.message]
    assert w.severity == "warning" and w.pointer == "/publishers/1/topics/1"
    assert w.location is not None and w.location.line == 21


def test_lexical_forms_of_the_original_grammar() -> None:
    m = _load(DATA / "lexical_forms.collector")
    assert m["drone"]["name"] == "boat"
    assert [v["name"] for v in m["drone"]["sensors"][0]["variables"]] == ["Sensor", "gyro_z"]
    assert m["pubBroker"] == {
        "name": "onboard",
        "endpoint": {"host": "localhost", "port": 7171},
        "logPath": "logs",
    }
    assert m["subBroker"]["name"] == "base" and m["subBroker"]["configPath"] == "conf"
    assert m["publishers"][0]["name"] == "p1"
    assert m["publishers"][0]["periodS"] == "0.04"
    assert m["publishers"][0]["topics"] == ["boat.imu.Sensor", "boat.imu.gyro_z"]
    assert [s["name"] for s in m["subscribers"]] == ["s1", "s2"]
    assert [s["periodS"] for s in m["subscribers"]] == ["2.0", "5.0"]
    assert m["subscribers"][0]["endpoint"]["host"] == "127.0.0.1"


def test_short_topic_references_resolve_when_unambiguous() -> None:
    text = (
        (DATA / "original_example.collector")
        .read_text()
        .replace('"usv.thermometer.temperature", 4.0E0', "temperature, 4.0E0")
        .replace('"usv.accelerometer.accel_z", .25', "'accelerometer.accel_z', .25")
    )
    m = load_text(text, "short.collector").model
    assert m is not None
    assert m["subscribers"][2]["topic"] == "usv.thermometer.temperature"
    assert m["subscribers"][1]["topic"] == "usv.accelerometer.accel_z"
    # a short name two sensors share stays as written: an unknown topic, located
    both = text.replace(
        "temperature(DEGREE_CELSIUS);", "temperature(DEGREE_CELSIUS); accel_x(NONE);"
    )
    twice = load_text(both.replace('"usv.accelerometer.accel_x", 2.0', "accel_x, 2.0"), "x")
    assert any("unknown topic 'accel_x'" in d.message for d in twice.errors)


def test_string_escapes_and_newlines() -> None:
    text = (
        (DATA / "lexical_forms.collector")
        .read_text()
        .replace("'logs'", "'lo\\tgs\\u00e9\\'\nnext'")
    )
    m = load_text(text, "esc.collector").model
    assert m is not None and m["pubBroker"]["logPath"] == "lo\tgsé'\nnext"


@pytest.mark.parametrize(
    "number,canonical", [("4.0E-2", "0.04"), ("2E0", "2.0"), ("0.5e1", "5.0"), (".25e+1", "2.5")]
)
def test_exponent_numbers(number: str, canonical: str) -> None:
    text = (DATA / "lexical_forms.collector").read_text().replace("4.0E-2", number)
    m = load_text(text, "n.collector").model
    assert m is not None and m["publishers"][0]["periodS"] == canonical


def test_huge_exponent_is_a_located_error_not_a_hang() -> None:
    text = (DATA / "lexical_forms.collector").read_text().replace("4.0E-2", "1E999999999")
    result = load_text(text, "big.collector")
    assert not result.ok
    [err] = [d for d in result.errors if "out of range" in d.message]
    assert err.location is not None and err.location.line == 16


def test_quoted_name_still_follows_the_identifier_rule() -> None:
    text = (DATA / "lexical_forms.collector").read_text().replace('"p1"', '"p 1"')
    result = load_text(text, "bad.collector")
    assert not result.ok
    assert any(
        d.pointer == "/publishers/0/name" and d.location and d.location.line == 16
        for d in result.errors
    ), [str(d) for d in result.diagnostics]


def test_runaway_string_points_at_its_start() -> None:
    text = (DATA / "lexical_forms.collector").read_text().replace("'logs'", "'logs")
    result = load_text(text, "open.collector")
    [err] = result.errors
    assert "closing quote missing" in err.message
    assert err.location is not None and err.location.line == 13


def test_windows_1252_file_is_detected(tmp_path: Path) -> None:
    text = (
        "// Capteur de température, 25 °C – essai\n"
        + (DATA / "original_example.collector").read_text()
    )
    f = tmp_path / "cp1252.collector"
    f.write_bytes(text.encode("cp1252"))
    result = load_file(f)
    assert result.ok
    assert any("windows-1252" in d.message and d.severity == "warning" for d in result.diagnostics)
    assert result.model == _load(DATA / "original_example.collector")
    # --encoding makes it exact: as UTF-8 the same bytes are a located error
    strict = load_file(f, "utf-8")
    assert not strict.ok
    [err] = strict.errors
    assert err.location is not None and (err.location.line, err.location.col) == (1, 19)
    assert "0xe9" in err.message


def test_utf8_with_bom_loads(tmp_path: Path) -> None:
    f = tmp_path / "bom.collector"
    f.write_bytes(b"\xef\xbb\xbf" + (DATA / "original_example.collector").read_bytes())
    result = load_file(f)
    assert result.ok and not any("windows" in d.message for d in result.diagnostics)


# -- export back -------------------------------------------------------------


@pytest.mark.parametrize(
    "name", ["original_example.collector", "lexical_forms.collector", "all_words.collector"]
)
def test_collector_round_trip(name: str) -> None:
    model = _load(DATA / name)
    text, omitted = print_collector(model)
    assert omitted == []
    assert text.startswith("DataCollector {\n")
    again = load_text(text, "again.collector")
    assert again.ok and again.model == model
    assert print_collector(model)[0] == print_collector(again.model)[0]


def test_scenarios_export_and_load_back(scenarios_dir: Path) -> None:
    for n in (1, 2):
        model = load_model(scenarios_dir / f"scenario{n}.modd")
        text, omitted = print_collector(model)
        assert omitted == []
        back = load_text(text, f"s{n}.collector").model
        assert back is not None
        # the original requires broker names: the defaults are written
        assert back["pubBroker"].pop("name") == "broker"
        assert back["subBroker"].pop("name") == "base"
        assert back == model


def test_demo_export_says_what_it_leaves_out() -> None:
    demo = load_model(Path(__file__).parents[1] / "examples" / "demo.modd")
    text, omitted = print_collector(demo)
    back = load_text(text, "demo.collector")
    assert back.ok, [str(d) for d in back.errors]
    pointers = {d.pointer for d in omitted}
    for i, s in enumerate(demo["drone"]["sensors"]):
        if s.get("kind") == "mavlink":
            assert f"/drone/sensors/{i}/kind" in pointers
    for i, sub in enumerate(demo["subscribers"]):
        kept = "endpoint" in sub and sub["aggregation"] in ORIGINAL_AGGREGATIONS
        assert (f"/subscribers/{i}" not in pointers) == kept
    assert all(d.severity == "warning" and "left out" in d.message for d in omitted)


def _paper_name(unit: str) -> str:
    """The paper's keyword for a unit: itself, the keyword whose UDUNITS spelling it is
    (``m`` is METER), else NONE."""
    if unit in KNOWN_UNITS:
        return unit
    return {text: k for k, text in PAPER_UNITS.items()}.get(unit, "NONE")


def _expressible(doc: dict[str, Any]) -> dict[str, Any]:
    """What the original form keeps of ``doc``."""
    out: dict[str, Any] = {"schemaVersion": doc["schemaVersion"]}
    out["drone"] = {
        "name": doc["drone"]["name"],
        "sensors": [
            {
                "name": s["name"],
                "variables": [
                    {"name": v["name"], "unit": _paper_name(v["unit"])} for v in s["variables"]
                ],
            }
            for s in doc["drone"]["sensors"]
        ],
    }
    for key, path, default in (
        ("pubBroker", "logPath", "broker"),
        ("subBroker", "configPath", "base"),
    ):
        b = doc[key]
        out[key] = {"name": b.get("name", default), "endpoint": b["endpoint"], path: b[path]}
    out["publishers"] = [
        {
            "name": p["name"],
            "endpoint": p.get("endpoint", doc["pubBroker"]["endpoint"]),
            "periodS": p["periodS"],
            "topics": p["topics"],
        }
        for p in doc["publishers"]
    ]
    out["subscribers"] = [
        {
            "name": s["name"],
            "endpoint": s["endpoint"],
            "topic": s["topic"],
            "periodS": s["periodS"],
            "aggregation": s["aggregation"],
        }
        for s in doc["subscribers"]
        if "endpoint" in s and s["aggregation"] in ORIGINAL_AGGREGATIONS
    ]
    return out


@settings(max_examples=100, deadline=None)
@given(documents())
def test_any_document_exports_to_what_the_original_form_keeps(doc: dict[str, Any]) -> None:
    text, _ = print_collector(doc)
    back = load_text(text, "gen.collector").model
    assert back == _expressible(doc)


# -- the command line ----------------------------------------------------------


def test_convert_to_collector_cli(tmp_path: Path) -> None:
    demo = Path(__file__).parents[1] / "examples" / "demo.modd"
    out = tmp_path / "demo.collector"
    res = subprocess.run(
        [*MODD, "convert", str(demo), "--to", "collector", "-o", str(out)],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert res.returncode == 0, res.stderr
    assert "left out of the .collector form" in res.stderr
    assert load_file(out).ok
    back = subprocess.run(
        [*MODD, "convert", str(out), "--to", "modd"], capture_output=True, text=True, timeout=180
    )
    assert back.returncode == 0 and back.stdout.startswith("Drone ")


def test_validate_with_encoding_option(tmp_path: Path) -> None:
    f = tmp_path / "latin.collector"
    f.write_bytes(("// é\n" + (DATA / "original_example.collector").read_text()).encode("latin-1"))
    res = subprocess.run(
        [*MODD, "validate", "--encoding", "utf-8", str(f)],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert res.returncode == 1 and f"{f}:1:4: error: byte 0xe9" in res.stderr
    ok = subprocess.run(
        [*MODD, "validate", "--encoding", "latin-1", str(f)],
        capture_output=True,
        text=True,
        timeout=180,
    )
    assert ok.returncode == 0, ok.stderr
