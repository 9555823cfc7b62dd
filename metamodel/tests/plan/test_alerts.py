"""Alerts in the model: a THRESHOLD subscriber's ``alert`` (the roles whose
views show it) read and printed back by the language, located errors, and the
stream the plan sends for it (both crossings, so the way back clears it)."""

from __future__ import annotations

import pytest
from modd_model import load_text, validate
from modd_model.printer import print_model
from modd_plan.plan import make_plan

from .test_events_plan import X, _text


def test_an_alert_reads_prints_back_and_streams_both_crossings() -> None:
    loaded = load_text(
        _text(
            f'Subscriber hi("{X}", 1.0, THRESHOLD(UP 0.5, 0.1), alert = scientist + operator);',
            f'Subscriber plain("{X}", 1.0, THRESHOLD(UP 0.5, 0.1));',
        ),
        "m.modd",
    )
    assert not loaded.errors and loaded.model is not None, loaded.errors
    hi, plain = loaded.model["subscribers"]
    assert hi["alert"] == ["scientist", "operator"] and hi["crossing"] == "up"
    assert "alert" not in plain
    assert load_text(print_model(loaded.model), "again.modd").model == loaded.model
    streams = {
        s.stream.aggregation: list(s.subscribers) for s in make_plan(loaded.model).sent_streams
    }
    assert streams == {"THRESHOLD(BOTH 0.5, 0.1)": ["hi"], "THRESHOLD(UP 0.5, 0.1)": ["plain"]}


@pytest.mark.parametrize(
    ("written", "message", "pointer"),
    [
        ("AVERAGE, alert = scientist", "only a THRESHOLD subscription can be an alert", "alert"),
        ("THRESHOLD(UP 1), alert = pilot", "role 'pilot' unknown", "alert/0"),
        ("THRESHOLD(UP 1), alert = operator + operator", "role 'operator' twice", "alert/1"),
    ],
)
def test_a_bad_alert_is_a_located_error(written: str, message: str, pointer: str) -> None:
    text = _text(f'Subscriber a("{X}", 1.0, {written});')
    errors = [e for e in load_text(text, "m.modd").errors if message in str(e)]
    assert len(errors) == 1, load_text(text, "m.modd").errors
    assert f"/subscribers/0/{pointer}" in str(errors[0])
    assert str(errors[0]).startswith("m.modd:")


def test_a_json_alert_with_an_unknown_role_is_refused_by_the_schema() -> None:
    text = _text(f'Subscriber a("{X}", 1.0, THRESHOLD(UP 1), alert = scientist);')
    model = load_text(text, "m.modd").model
    assert model is not None
    model["subscribers"][0]["alert"] = ["captain"]
    errors = validate(model)
    assert any("/subscribers/0/alert/0" in str(e) for e in errors), errors
