"""Declared resolution (docs/dsl.md, "Resolution"): a variable's and a
subscription's, parsed, printed back (modd fmt), and every bad one located."""

from __future__ import annotations

import json

import pytest
from modd_model import load_text
from modd_model.printer import print_model
from modd_model.validate import validate

MODEL = """\
Drone usv {
    Sensors {
        Sensor imu measures {
            ax(METER_PER_SECOND_SQUARED) { validMin = -20; validMax = 20; resolution = 0.01; };
            az(METER_PER_SECOND_SQUARED);
        }
    }
}
PubBroker("127.0.0.1":7171, "/logs");
SubBroker("127.0.0.1":7272, "/conf");
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.imu.ax", "usv.imu.az");
}
Subscriptions {
    Subscriber sub_1("usv.imu.ax", 0.25, AVERAGE, backfill = gaps, resolution = 0.05);
    Subscriber sub_2("usv.imu.az", 0.25, MIN, resolution = 1e-3);
    Subscriber sub_3("usv.imu.ax", 0.25, MAX);
}
"""


def test_resolutions_parse_and_print_back() -> None:
    result = load_text(MODEL, "m.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    ax = result.model["drone"]["sensors"][0]["variables"][0]
    assert (ax["resolution"], ax["validMin"], ax["validMax"]) == (0.01, -20, 20)
    subs = {s["name"]: s for s in result.model["subscribers"]}
    assert subs["sub_1"]["resolution"] == 0.05 and subs["sub_2"]["resolution"] == 0.001
    assert "resolution" not in subs["sub_3"]
    printed = print_model(result.model)
    assert "backfill = gaps, resolution = 0.05);" in printed and "resolution = 0.01;" in printed
    assert load_text(printed, "p.modd").model == result.model


def _errors(text: str) -> list[tuple[str, int, str]]:
    result = load_text(text, "m.modd")
    return [
        (d.message, d.location.line if d.location else 0, d.pointer)
        for d in result.diagnostics
        if d.severity == "error"
    ]


@pytest.mark.parametrize(
    ("old", "new", "pointer", "words"),
    [
        (
            'sub_2("usv.imu.az", 0.25, MIN, resolution = 1e-3)',
            'sub_2("usv.imu.ax", 0.25, MIN, resolution = 1e-3)',
            "/subscribers/1/resolution",
            "finer than its variable's",
        ),
        ("resolution = 0.05)", "resolution = 0)", "/subscribers/0/resolution", "0"),
        (
            "resolution = 0.01;",
            "resolution = -0.01;",
            "/drone/sensors/0/variables/0/resolution",
            "0",
        ),
        (
            "resolution = 0.01;",
            "resolution = 1e-18;",
            "/drone/sensors/0/variables/0/resolution",
            "2^53",
        ),
        (
            "validMin = -20; validMax = 20;",
            "validMin = 20; validMax = -20;",
            "/drone/sensors/0/variables/0/validMin",
            "above validMax",
        ),
    ],
)
def test_a_bad_resolution_is_located(old: str, new: str, pointer: str, words: str) -> None:
    assert old in MODEL
    errors = _errors(MODEL.replace(old, new))
    assert any(p == pointer and words in m and line > 0 for m, line, p in errors), errors


def test_nan_and_infinite_resolutions_are_refused() -> None:
    doc = load_text(MODEL, "m.modd").model
    assert doc is not None
    for bad in (float("nan"), float("inf")):
        doc["subscribers"][0]["resolution"] = bad
        doc["drone"]["sensors"][0]["variables"][0]["resolution"] = bad
        found = {d.pointer for d in validate(json.loads(json.dumps(doc)))}
        assert "/subscribers/0/resolution" in found
        assert "/drone/sensors/0/variables/0/resolution" in found
