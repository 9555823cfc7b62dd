"""MEDIAN, STDDEV and RANGE: exact over the window (numpy's, through the
contract's vectors), derived from ALL only, sized by the planner, and bounded
on board (a located error past MAX_LIST samples a window)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from modd_contracts import aggregations_gen as agg
from modd_contracts.link_wire_gen import MAX_LIST
from modd_model.validate import validate
from modd_plan.derive import aggregate, derive_value, percentile
from modd_plan.plan import make_plan

VECTORS = Path(__file__).resolve().parents[3] / "contracts" / "vectors"
NEW = (agg.MEDIAN, agg.STDDEV, agg.RANGE)


def _cases() -> list[dict[str, Any]]:
    doc = json.loads((VECTORS / "aggregations.json").read_text(encoding="utf-8"))
    cases: list[dict[str, Any]] = doc["vectors"]
    return cases


def test_the_generator_reproduces_the_committed_vectors() -> None:
    spec = importlib.util.spec_from_file_location(
        "gen_aggregations", VECTORS / "gen_aggregations.py"
    )
    assert spec and spec.loader
    gen = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gen)
    assert gen.text() == (VECTORS / "aggregations.json").read_text(encoding="utf-8")


@pytest.mark.parametrize("case", _cases(), ids=lambda c: c["name"])
def test_aggregate_equals_numpy_over_the_window(case: dict[str, Any]) -> None:
    samples = case["samples"]
    assert aggregate(agg.MEDIAN, samples) == case["MEDIAN"]
    assert aggregate(agg.STDDEV, samples) == pytest.approx(case["STDDEV"], rel=1e-9)
    assert aggregate(agg.RANGE, samples) == case["RANGE"]
    # and numpy itself, at the same call, agrees (the vectors are not stale)
    assert case["MEDIAN"] == float(np.median(np.asarray(samples, np.float64)))


@pytest.mark.parametrize("case", _cases(), ids=lambda c: c["name"])
def test_percentile_equals_numpy_over_the_window(case: dict[str, Any]) -> None:
    samples = case["samples"]
    x = np.asarray(samples, np.float64)
    assert len(case["PERCENTILE"]) >= 8
    for key, want in case["PERCENTILE"].items():
        p = float(key)
        assert percentile(samples, p) == want, (key, case["name"])  # to the bit
        assert want == float(np.percentile(x, p, method="linear"))  # not stale
    assert percentile(samples, 50) == pytest.approx(case["MEDIAN"], rel=1e-15, abs=1e-300)


def test_percentile_equals_numpy_over_random_windows() -> None:
    rng = np.random.default_rng(95)
    for _ in range(300):
        n = int(rng.integers(1, 200))
        x = rng.normal(rng.uniform(-1e6, 1e6), rng.uniform(1e-3, 1e3), n)
        x[rng.random(n) < 0.1] = 0.0  # ties
        p = float(rng.choice([rng.uniform(1e-9, 100), 95.0, 100.0, 0.5]))
        assert percentile(list(x), p) == float(np.percentile(x, p)), (n, p)


@pytest.mark.parametrize("p", [-5, 100.5, float("nan"), float("inf")])
def test_a_percentile_outside_0_100_is_refused(p: float) -> None:
    with pytest.raises(ValueError, match=r"not in \[0, 100\]"):
        percentile([1.0, 2.0], p)
    assert percentile([2.0, 1.0], 0) == float(np.percentile([2.0, 1.0], 0)) == 1.0


def test_an_empty_window_is_absent() -> None:
    assert all(aggregate(a, []) is None for a in NEW)


def test_derived_from_all_over_the_whole_window_not_per_window() -> None:
    halves = [[1.0, 2.0, 100.0], [3.0, 4.0]]
    whole = [*halves[0], *halves[1]]
    for a in NEW:
        got = derive_value(a, [(agg.ALL, halves)])
        assert got == pytest.approx(aggregate(a, whole)), a
    assert derive_value(agg.MEDIAN, [(agg.ALL, halves)]) == 3.0  # not the median of medians
    with pytest.raises(ValueError):
        derive_value(agg.MEDIAN, [(agg.MEDIAN, [2.0, 3.5])])


def test_planner_sends_a_median_at_its_period_and_never_merges_medians(make_model: Any) -> None:
    model = make_model(
        ["t"],
        [("p", "0.1", ["t"])],
        [
            ("m1", "t", "1.0", agg.MEDIAN),
            ("m2", "t", "2.0", agg.MEDIAN),
            ("s", "t", "1.0", "STDDEV"),
        ],
    )
    plan = make_plan(model)
    sent = {(s.stream.aggregation, float(s.stream.period)) for s in plan.sent_streams}
    assert (agg.MEDIAN, 1.0) in sent and (agg.MEDIAN, 2.0) in sent
    assert (agg.STDDEV, 1.0) in sent
    assert plan.link.drone_to_base > 0


def test_a_window_past_the_bound_is_a_located_error(make_model: Any) -> None:
    period = 0.01 * (MAX_LIST + 1)
    model = make_model(["t"], [("p", "0.01", ["t"])], [("m", "t", f"{period:g}", agg.MEDIAN)])
    errors = [d for d in validate(model) if "keeps at most" in d.message]
    assert len(errors) == 1 and errors[0].pointer == "/subscribers/0/periodS", errors
    assert "655.35 s" in errors[0].message
    fits = make_model(["t"], [("p", "0.01", ["t"])], [("m", "t", "655.35", agg.MEDIAN)])
    assert not [d for d in validate(fits) if "keeps at most" in d.message]
    stddev = make_model(["t"], [("p", "0.01", ["t"])], [("m", "t", f"{period:g}", "STDDEV")])
    assert not [d for d in validate(stddev) if "keeps at most" in d.message]  # no samples kept


def test_bool_topics_refuse_the_new_statistics(make_model: Any) -> None:
    for a in NEW:
        model = make_model([("b", "bool")], [("p", "0.1", ["b"])], [("s", "b", "1.0", a)])
        assert any(d.pointer == "/subscribers/0/aggregation" for d in validate(model)), a


def test_the_bound_error_is_located_in_the_modd_text() -> None:
    from modd_model import load_text

    scenario = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "scenario1.modd"
    text = scenario.read_text(encoding="utf-8").replace("2.0, AVERAGE);", "3000.0, MEDIAN);", 1)
    (error,) = [e for e in load_text(text, "m.modd").errors if "keeps at most" in str(e)]
    assert str(error).startswith(
        "m.modd:19:69: error: a MEDIAN window of 3000.0 s holds up to 75000"
    )
