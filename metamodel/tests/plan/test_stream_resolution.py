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
    assert exact.data_to_base == 81.6
    assert quantised.data_to_base == pytest.approx(0.8 * 47)


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
    # (4 x coarser before the link's control traffic was counted: its bound
    # takes 31 of the 36 s an hour)
    assert "resolution 16 x coarser" in coarser[0].describe()
    assert coarser[0].model["drone"]["sensors"][0]["variables"][0]["resolution"] == 0.016
    figures = [(p.accepted_delay_s, p.min_period_s, p.report.bytes_per_s) for p in plan.proposals]
    assert len(set(figures)) == len(figures)  # no coarser twin of the same plan


def _codec_bytes(*values: float) -> int:
    """Bytes the link's codec (modd.link.codec, the runtime's) writes for one
    stream's ``values`` in one datagram at 0.01."""
    from modd.link.codec import put_number

    b: bytearray = bytearray()
    chain: dict[int, int] = {}
    for x in values:
        put_number(b, chain, 0, x, 0.01)
    return len(b)


def test_the_radio_figures_say_whether_they_bound_the_link() -> None:
    model = _scenario1()
    model["link"] = {"transport": "serial", "device": "/dev/x", "radio": {"kind": "sik"}}
    assert make_plan(model).radio.upper_bound is None  # type: ignore[union-attr]  # exact
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01)
    # no range: the absolute values' size is a guess, and nothing bounds it
    unranged = make_plan(model).radio
    assert unranged is not None and unranged.upper_bound is False and unranged.ceiling is None
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(validMin=-20, validMax=20)
    # 5 windows a datagram, deltas assumed 1 B: an estimate, and its bound
    estimate = make_plan(model).radio
    assert estimate is not None and estimate.upper_bound is False and estimate.ceiling
    assert estimate.ceiling.upper_bound is True
    # the bound: each value as the codec writes the range's worst, an absolute
    # -20 then a delta to +20, 2 B each: 4 values x 5 slots x 2 B + 10 counts,
    # + 8 header and tag + 4 serial framing, 0.8 datagrams a second
    assert _codec_bytes(-20.0) == 2 and _codec_bytes(-20.0, 20.0) == 4
    # with the control traffic's bound: a PONG of at most 25 B every 30 s, a
    # STATUS of at most the 252-B packet every 60 s (control.py)
    control = (25 * 120 + 252 * 60) / 3600
    assert estimate.ceiling.bytes_per_s == pytest.approx(0.8 * (4 * 5 * 2 + 10 + 12) + control)
    assert estimate.ceiling.air_s_per_hour > estimate.air_s_per_hour
    assert estimate.duty_share is None  # sik: no limit
    # the plan JSON says so, for the Plan panel (the contract: plan.schema.json)
    doc = estimate.to_json()
    assert doc["figures"] == "estimate"
    assert doc["air_time_bound_s_per_hour"] == round(estimate.ceiling.air_s_per_hour, 3)
    # under the windows' period, every datagram holds one window: every value
    # absolute, sized at the range: the DATA's figures are their bound; with
    # the control traffic (an estimate) the figures are "about", their bound
    # the DATA's with the control's
    model["link"]["acceptedDelayS"] = "0.2"
    bounded = make_plan(model).radio
    assert bounded is not None and bounded.upper_bound is True and bounded.ceiling
    assert bounded.at_most == "about " and bounded.ceiling.at_most == "at most "
    assert bounded.to_json()["figures"] == "estimate"
    data = bounded.air_s_per_hour - bounded.control_s_per_hour
    assert bounded.ceiling.air_s_per_hour - bounded.ceiling.control_s_per_hour == pytest.approx(
        data
    )
    assert bounded.to_json()["air_time_bound_s_per_hour"] == round(
        bounded.ceiling.air_s_per_hour, 3
    )


def test_a_plan_is_refused_on_its_bound() -> None:
    model = _scenario1()
    model["link"] = {
        "transport": "serial",
        "device": "/dev/x",
        "radio": {"kind": "lora", "dutyCycle": "0.5"},
    }
    for v in model["drone"]["sensors"][0]["variables"]:
        v.update(resolution=0.01, validMin=-20, validMax=20)
    # between the estimate and the bound: the limit is checked on the bound
    report = make_plan(model).radio
    assert report is not None and report.ceiling is not None
    duty = round((report.air_s_per_hour + report.ceiling.air_s_per_hour) / 2 / 3600, 4)
    model["link"]["radio"]["dutyCycle"] = str(duty)
    between = make_plan(model).radio
    assert between is not None and between.ceiling is not None
    assert between.air_s_per_hour < duty * 3600 < between.ceiling.air_s_per_hour
    assert not between.fits and between.error and "at most" in between.error
    assert all(p.report.fits for p in make_plan(model).proposals)
