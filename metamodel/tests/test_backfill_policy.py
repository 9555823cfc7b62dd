"""The subscription's backfill policy (off, gaps, mission): parsed, printed
back, an unknown word located."""

from __future__ import annotations

from modd_model import load_text
from modd_model.printer import print_model

MODEL = """\
Drone usv {
    Sensors {
        Sensor imu measures {
            ax(METER_PER_SECOND_SQUARED);
        }
    }
}
PubBroker("127.0.0.1":7171, "/logs");
SubBroker("127.0.0.1":7272, "/conf");
Publishers {
    Publisher pub_1("127.0.0.1":7373, 0.04, "usv.imu.ax");
}
Subscriptions {
    Subscriber sub_1("127.0.0.1":7401, "usv.imu.ax", 2.0, AVERAGE, backfill = gaps);
    Subscriber sub_2("usv.imu.ax", 0.25, MIN);
}
"""


def test_policy_parses_and_prints_back() -> None:
    result = load_text(MODEL, "m.modd")
    assert result.ok and result.model is not None, [str(d) for d in result.diagnostics]
    subs = {s["name"]: s for s in result.model["subscribers"]}
    assert subs["sub_1"]["backfill"] == "gaps"
    assert "backfill" not in subs["sub_2"]  # off by default
    printed = print_model(result.model)
    assert "AVERAGE, backfill = gaps);" in printed
    assert load_text(printed, "p.modd").model == result.model


def test_unknown_policy_is_located() -> None:
    result = load_text(MODEL.replace("backfill = gaps", "backfill = always"), "m.modd")
    hits = [d for d in result.diagnostics if "unknown backfill policy 'always'" in d.message]
    assert hits, [str(d) for d in result.diagnostics]
    assert hits[0].pointer == "/subscribers/0/backfill"
    assert hits[0].location is not None and hits[0].location.line == 14
