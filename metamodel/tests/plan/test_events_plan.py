"""Event subscriptions in the model and the plan: the language's
``ON_CHANGE(0.5)``, ``ON_CHANGE(5%)``, ``THRESHOLD(DOWN 5.0, 0.2)`` and
``maxEvents = N`` read and printed back, located errors, the stream labels, and
the worst-case sizes the plan counts (every window at N events)."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path

import pytest
from modd_model import load_text
from modd_model.printer import print_model
from modd_plan.linkcost import event_window_bytes, window_value_bytes
from modd_plan.plan import make_plan

SCENARIO = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "scenario1.modd"
X = "usv.accelerometer.accel_x"


def _text(*lines: str) -> str:
    """Scenario 1 with these subscribers instead of its own (25 Hz topics)."""
    text = SCENARIO.read_text(encoding="utf-8")
    head = text[: text.index("Subscriptions {")]
    return head + "Subscriptions {\n" + "\n".join(f"    {x}" for x in lines) + "\n}\n"


def test_the_language_reads_and_prints_events() -> None:
    loaded = load_text(
        _text(
            f'Subscriber a("{X}", 1.0, ON_CHANGE(0.5), maxEvents = 4);',
            f'Subscriber b("{X}", 1.0, ON_CHANGE(5%));',
            f'Subscriber c("{X}", 0.5, THRESHOLD(DOWN 5.0, 0.2), maxEvents = 2);',
            f'Subscriber d("{X}", 1.0, THRESHOLD(-2));',
            f'Subscriber e("{X}", 1.0, ON_CHANGE);',
        ),
        "m.modd",
    )
    assert not loaded.errors and loaded.model is not None, loaded.errors
    a, b, c, d, e = loaded.model["subscribers"]
    assert (a["deadband"], a["maxEvents"], b["deadbandPercent"]) == (0.5, 4, 5.0)
    assert (c["crossing"], c["level"], c["hysteresis"]) == ("down", 5.0, 0.2)
    assert d["level"] == -2.0 and "crossing" not in d and e == {**e, "aggregation": "ON_CHANGE"}
    again = load_text(print_model(loaded.model), "again.modd")
    assert again.model == loaded.model
    plan = make_plan(loaded.model)
    assert {s.stream.aggregation for s in plan.sent_streams} == {
        "ON_CHANGE(0.5, 4)",
        "ON_CHANGE(5%)",
        "THRESHOLD(DOWN 5, 0.2, 2)",
        "THRESHOLD(BOTH -2)",
        "ON_CHANGE(0)",
    }


@pytest.mark.parametrize(
    ("written", "message", "pointer"),
    [
        ("AVERAGE(5%)", "AVERAGE takes no such parameters", "aggregation"),
        ("ON_CHANGE(UP 5)", "ON_CHANGE takes no such parameters", "aggregation"),
        ("THRESHOLD(SIDEWAYS 5)", "unknown crossing 'SIDEWAYS'", "crossing"),
        ("THRESHOLD", "THRESHOLD needs its level", "aggregation"),
        ("ON_CHANGE(-1)", "less than the minimum of 0", "deadband"),
        ("MIN, maxEvents = 3", "MIN takes no maxEvents", "maxEvents"),
        ("ON_CHANGE(1), maxEvents = 0", "less than the minimum of 1", "maxEvents"),
        ("ON_CHANGE(1), resolution = 0.1", "takes no resolution", "resolution"),
    ],
)
def test_a_bad_event_subscription_is_a_located_error(
    written: str, message: str, pointer: str
) -> None:
    text = _text(f'Subscriber a("{X}", 1.0, {written});')
    errors = [e for e in load_text(text, "m.modd").errors if message in str(e)]
    assert len(errors) == 1, load_text(text, "m.modd").errors
    assert f"/subscribers/0/{pointer}" in str(errors[0])
    assert str(errors[0]).startswith("m.modd:")  # located in the text


@pytest.mark.parametrize("policy", ["gaps", "mission"])
def test_an_event_subscription_is_backfilled_like_a_window(policy: str) -> None:
    text = _text(f'Subscriber a("{X}", 1.0, THRESHOLD(UP 5, 0.2), backfill = {policy});')
    loaded = load_text(text, "m.modd")
    assert not loaded.errors, loaded.errors


def test_a_derived_worst_case_is_bounded_like_a_median() -> None:
    text = _text(f'Subscriber a("{X}", 3000.0, ON_CHANGE(1));')  # 75,000 samples a window
    (error,) = [e for e in load_text(text, "m.modd").errors if "keeps at most" in str(e)]
    assert "declare maxEvents" in str(error)
    ok = _text(f'Subscriber a("{X}", 3000.0, ON_CHANGE(1), maxEvents = 10);')
    assert not load_text(ok, "m.modd").errors


def test_the_plan_counts_every_window_at_its_worst() -> None:
    # 25 samples a 1-s window; N = 4: count, 4 x (3-B time + f32), coalesced <= 21
    assert event_window_bytes("ON_CHANGE(0.5, 4)", "float32", Fraction(25), 1_000_000) == 30
    # derived: every sample, 25 events
    assert (
        event_window_bytes("THRESHOLD(UP 5)", "float64", Fraction(25), 1_000_000) == 1 + 25 * 11 + 1
    )
    assert window_value_bytes("ON_CHANGE(0.5, 4)", "int", Fraction(2), 1_000_000) == 1 + 2 * 13 + 1
    loaded = load_text(_text(f'Subscriber a("{X}", 1.0, ON_CHANGE(0.5), maxEvents = 4);'), "m.modd")
    assert loaded.model is not None
    doc = make_plan(loaded.model).to_json()
    (stream,) = doc["streams"]
    assert (stream["events_at_most"], stream["bytes_per_s_at_most"]) == (4, 30.0)
    quiet = load_text(_text(f'Subscriber a("{X}", 1.0, LAST);'), "m.modd").model
    assert quiet is not None
    last = make_plan(quiet).to_json()["predicted_link_bytes_per_s"]["drone_to_base"]
    assert doc["predicted_link_bytes_per_s"]["drone_to_base"] == last + 30 - 4  # f32 LAST: 4 B
