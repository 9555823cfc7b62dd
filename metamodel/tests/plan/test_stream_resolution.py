"""Which resolution each sent stream goes with (modd_plan.resolution): the finest
of its subscribers' (directly or through derived streams), None when one needs
full precision; a SUM source of k windows k times finer."""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_model
from modd_plan import make_plan
from modd_plan.resolution import stream_resolutions

SCENARIO1 = Path(__file__).resolve().parents[2] / "examples" / "scenarios" / "scenario1.modd"


def _resolutions(model: dict[str, Any]) -> dict[str, float | None]:
    plan = make_plan(model)
    sent = plan.sent_streams
    return {
        s.stream.key: r
        for s, r in zip(sent, stream_resolutions(model, sent, plan.streams), strict=True)
    }


def _scenario1(**by_variable: float) -> dict[str, Any]:
    model = copy.deepcopy(load_model(SCENARIO1))
    for v in model["drone"]["sensors"][0]["variables"]:
        if v["name"] in by_variable:
            v["resolution"] = by_variable[v["name"]]
    return model


def test_scenario1_at_a_centimetre_per_second_squared() -> None:
    got = _resolutions(_scenario1(accel_x=0.01, accel_y=0.01, accel_z=0.01))
    assert len(got) == 4 and set(got.values()) == {0.01}  # the 2 s AVERAGEs derive from 0.25 s


def test_the_finest_subscriber_wins_and_one_without_keeps_full_precision() -> None:
    model = _scenario1(accel_x=0.01)
    subs = {s["name"]: s for s in model["subscribers"]}
    subs["sub_1"]["resolution"] = 0.2  # coarser on the 2 s AVERAGE of x, 0.01 on the 0.25 s one
    subs["sub_5"]["resolution"] = 0.05  # MIN z: only this subscriber
    subs["sub_6"]["resolution"] = 0.05  # MAX z: sub_7 declares none, its variable neither
    by_topic = {(k.split("/")[0], k.split("/")[1]): r for k, r in _resolutions(model).items()}
    assert by_topic[("usv.accelerometer.accel_x", "AVERAGE")] == 0.01
    assert by_topic[("usv.accelerometer.accel_y", "AVERAGE")] is None
    assert by_topic[("usv.accelerometer.accel_z", "MIN")] == 0.05
    assert by_topic[("usv.accelerometer.accel_z", "MAX")] is None


def test_a_sum_source_is_sent_finer_by_its_factor() -> None:
    model = _scenario1(accel_x=0.01)
    model["subscribers"] = [
        {
            "name": "s_fast",
            "topic": "usv.accelerometer.accel_x",
            "periodS": "0.25",
            "aggregation": "SUM",
            "resolution": 0.08,
        },
        {
            "name": "s_slow",
            "topic": "usv.accelerometer.accel_x",
            "periodS": "1",
            "aggregation": "SUM",
            "resolution": 0.2,
        },
    ]
    got = _resolutions(model)
    assert list(got.values()) == [0.05]  # 1 s from 4 windows: 0.2 / 4, finer than 0.08


def test_the_planner_counts_quantised_bytes() -> None:
    model = _scenario1()
    model["link"] = {"transport": "serial", "device": "/dev/x"}
    exact = make_plan(model).budget
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=-20, validMax=20)
    quantised = make_plan(model).budget
    assert exact is not None and quantised is not None
    # 5 slots a datagram: a 2-byte key (|q| <= 2000) then 1-byte deltas, per value
    # (2 AVERAGE + count, MIN, MAX): 4 x (2 + 4 x 1) + 10 counts = 34 B, the key
    # spread over the windows (1.2 B a value) and each slot rounded up to whole bytes
    # (7 B): 35 B, + 8 header and tag + 4 serial framing, 0.8 datagrams a second
    assert exact.drone_to_base == 81.6
    assert quantised.drone_to_base == pytest.approx(0.8 * 47)


def test_a_refused_radio_plan_may_be_proposed_coarser_resolutions() -> None:
    model = _scenario1()
    model["link"] = {
        "transport": "serial",
        "device": "/dev/x",
        "radio": {"kind": "lora", "spreadingFactor": 7, "bandwidthHz": 125000, "dutyCycle": "0.01"},
    }
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.001, validMin=-20, validMax=20)
    plan = make_plan(model)
    assert plan.radio is not None and not plan.radio.fits
    coarser = [p for p in plan.proposals if p.coarser is not None]
    assert coarser and all(p.report.fits for p in plan.proposals)
    assert "resolution 4 x coarser" in coarser[0].describe()
    assert coarser[0].model["drone"]["sensors"][0]["variables"][0]["resolution"] == 0.004
    figures = [(p.accepted_delay_s, p.min_period_s, p.report.bytes_per_s) for p in plan.proposals]
    assert len(set(figures)) == len(figures)  # no coarser twin of the same plan
