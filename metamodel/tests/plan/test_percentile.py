"""PERCENTILE(p) as an aggregation: the model's ``percentile`` and the
language's ``PERCENTILE(95)`` (located errors for a p out of 0..100, a
PERCENTILE without one, a p on another aggregation), the plan's stream label
(two p of one topic and period are two streams, in p order), sizes like an
AVERAGE, derived from ALL only, the on-board bound, and the CONFIG field."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from modd_contracts import aggregations_gen as agg
from modd_contracts import labels
from modd_model import load_text
from modd_model.printer import print_model
from modd_model.validate import validate
from modd_plan.derive import aggregate, derive_value
from modd_plan.linkcost import window_value_bytes
from modd_plan.plan import make_plan

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "scenario1.modd"


def _text(aggregation: str) -> str:
    return SCENARIO.read_text(encoding="utf-8").replace(
        "2.0, AVERAGE);", f"2.0, {aggregation});", 1
    )


def _pct(model: dict[str, Any], i: int, p: float | None) -> dict[str, Any]:
    sub = model["subscribers"][i]
    sub["aggregation"] = agg.PERCENTILE
    if p is not None:
        sub["percentile"] = p
    return model


def test_the_language_reads_and_prints_percentile() -> None:
    loaded = load_text(_text("PERCENTILE(95)"), "m.modd")
    assert not loaded.errors and loaded.model is not None
    sub = loaded.model["subscribers"][0]
    assert (sub["aggregation"], sub["percentile"]) == ("PERCENTILE", 95.0)
    printed = print_model(loaded.model)
    assert "PERCENTILE(95)" in printed
    assert load_text(printed, "again.modd").model == loaded.model
    decimal = load_text(_text("PERCENTILE(99.9)"), "m.modd").model
    assert decimal is not None and decimal["subscribers"][0]["percentile"] == 99.9


@pytest.mark.parametrize(
    ("written", "message", "pointer"),
    [
        ("PERCENTILE(150)", "150.0 is greater than the maximum of 100", "percentile"),
        ("PERCENTILE(-1)", "-1.0 is less than the minimum of 0", "percentile"),
        ("PERCENTILE", "PERCENTILE needs its p", "aggregation"),
        ("MEDIAN(5)", "MEDIAN takes no percentile", "percentile"),
    ],
)
def test_a_bad_percentile_is_a_located_error(written: str, message: str, pointer: str) -> None:
    text = _text(written)
    (error,) = [e for e in load_text(text, "m.modd").errors if message in str(e)]
    line = next(n for n, t in enumerate(text.splitlines(), 1) if written + ")" in t)
    assert str(error).startswith(f"m.modd:{line}:"), str(error)
    assert f"/subscribers/0/{pointer}" in str(error)


def test_json_models_say_the_same(scenario1_dict: dict[str, Any]) -> None:
    bad = _pct(scenario1_dict, 0, 100.5)
    assert [d.pointer for d in validate(bad) if d.severity == "error"] == [
        "/subscribers/0/percentile"
    ]
    assert not [d for d in validate(_pct(bad, 0, 0)) if d.severity == "error"]
    del bad["subscribers"][0]["percentile"]
    assert [d.pointer for d in validate(bad) if d.severity == "error"] == [
        "/subscribers/0/aggregation"
    ]


def test_plan_streams_are_labelled_and_ordered_by_p(make_model: Any) -> None:
    model = make_model(
        ["t"],
        [("p", "0.1", ["t"])],
        [
            ("a", "t", "1.0", agg.PERCENTILE),
            ("b", "t", "1.0", agg.PERCENTILE),
            ("m", "t", "1.0", "MEDIAN"),
        ],
    )
    model["subscribers"][0]["percentile"] = 95
    model["subscribers"][1]["percentile"] = 5
    plan = make_plan(model)
    assert [s.stream.aggregation for s in plan.sent_streams] == [
        "MEDIAN",
        "PERCENTILE(5)",
        "PERCENTILE(95)",
    ]
    one = Fraction(10)  # samples a window: one float32 value, as MEDIAN's and AVERAGE's mean
    assert window_value_bytes("PERCENTILE(95)", "float32", one) == 4
    assert window_value_bytes("PERCENTILE(95)", "int", one) == 8  # a float64, as MEDIAN's


def test_derived_from_all_only(make_model: Any) -> None:
    halves = [[1.0, 2.0, 100.0], [3.0, 4.0, 7.0]]
    want = float(np.percentile([*halves[0], *halves[1]], 95))
    assert derive_value("PERCENTILE(95)", [(agg.ALL, halves)]) == want
    with pytest.raises(ValueError):
        derive_value("PERCENTILE(95)", [("PERCENTILE(95)", [2.0, 3.5])])
    model = make_model(
        ["t"],
        [("p", "0.1", ["t"])],
        [("a", "t", "0.5", agg.ALL), ("q", "t", "1.0", agg.PERCENTILE)],
    )
    model["subscribers"][1]["percentile"] = 95
    plan = make_plan(model)
    assert [s.stream.aggregation for s in plan.sent_streams] == ["ALL"]
    assert aggregate("PERCENTILE(0)", [3.0, 1.0]) == 1.0 and aggregate("PERCENTILE(5)", []) is None


def test_the_window_bound_applies(make_model: Any) -> None:
    model = make_model(["t"], [("p", "0.01", ["t"])], [("q", "t", "700", agg.PERCENTILE)])
    model["subscribers"][0]["percentile"] = 50
    (error,) = [d for d in validate(model) if "keeps at most" in d.message]
    assert error.pointer == "/subscribers/0/periodS" and "PERCENTILE" in error.message


@pytest.mark.parametrize(
    "bad", ["PERCENTILE", "PERCENTILE(101)", "MEDIAN(5)", "PERCENTILE(x)", "X"]
)
def test_labels_refuse_what_is_not_one(bad: str) -> None:
    with pytest.raises(ValueError, match="unknown aggregation"):
        labels.parse(bad)
