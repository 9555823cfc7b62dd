"""Stream identity, ids in contract order, and the choice of sent streams."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

from modd_contracts.types_gen import PlanDocument, PlanStream
from modd_plan.plan import make_plan
from modd_plan.streams import StreamKey, find_sources

X = "d.accelerometer.accel_x"
Z = "d.accelerometer.accel_z"


def _by_key(plan_json: PlanDocument) -> dict[str, PlanStream]:
    return {s["key"]: s for s in plan_json["streams"]}


def test_scenario1_derives_the_2s_average_and_shares_the_max(scenario1_dict: Any) -> None:
    j = make_plan(scenario1_dict).to_json()
    streams = _by_key(j)
    avg2 = streams[f"{X}/AVERAGE/2.0"]
    assert (avg2["sent"], avg2["id"]) == (False, None)
    assert (avg2["derived_from"], avg2["factor"]) == (f"{X}/AVERAGE/0.25", 8)
    assert avg2["subscribers"] == ["sub_1"]
    assert streams[f"{X}/AVERAGE/0.25"]["subscribers"] == ["sub_3"]
    mx = streams[f"{Z}/MAX/0.25"]
    assert mx["subscribers"] == ["sub_6", "sub_7"] and mx["sent"]
    assert j["subscriptions"]["sub_6"] == j["subscriptions"]["sub_7"] == mx["key"]
    # ids: topic order, then aggregation enum order (MIN before MAX), then period
    sent = sorted((s for s in j["streams"] if s["sent"]), key=lambda s: s["id"] or 0)
    assert [s["key"] for s in sent] == [
        f"{X}/AVERAGE/0.25",
        "d.accelerometer.accel_y/AVERAGE/0.25",
        f"{Z}/MIN/0.25",
        f"{Z}/MAX/0.25",
    ]
    assert [s["id"] for s in sent] == [0, 1, 2, 3]


def test_min_is_not_derived_from_max_nor_from_a_non_multiple(make_model: Any) -> None:
    subs = [("a", "t", "0.5", "MAX"), ("b", "t", "1.0", "MIN"), ("c", "t", "0.75", "MAX")]
    j = make_plan(make_model(["t"], [("p", "0.1", ["t"])], subs)).to_json()
    assert all(s["sent"] for s in j["streams"])  # 0.75 is no multiple of 0.5
    assert [s["key"] for s in j["streams"]] == ["d.s.t/MIN/1.0", "d.s.t/MAX/0.5", "d.s.t/MAX/0.75"]


def test_all_feeds_every_aggregation_at_multiples(make_model: Any) -> None:
    subs = [
        ("a", "t", "0.5", "ALL"),
        ("b", "t", "1.0", "MIN"),
        ("c", "t", "0.5", "SUM"),
        ("d", "t", "1.5", "AVERAGE"),
        ("e", "t", "0.2", "LAST"),
    ]
    j = make_plan(make_model(["t"], [("p", "0.05", ["t"])], subs)).to_json()
    streams = _by_key(j)
    assert [k for k, s in streams.items() if s["sent"]] == ["d.s.t/LAST/0.2", "d.s.t/ALL/0.5"]
    assert streams["d.s.t/MIN/1.0"]["derived_from"] == "d.s.t/ALL/0.5"
    assert streams["d.s.t/MIN/1.0"]["factor"] == 2
    assert streams["d.s.t/AVERAGE/1.5"]["factor"] == 3


def test_a_helper_all_stream_when_raw_samples_are_cheaper(make_model: Any) -> None:
    # 2 samples per 1 s window: ALL = 1 + 2 x 4 B < MIN 4 + MAX 4 + AVERAGE 5 B
    subs = [("a", "t", "1.0", "MIN"), ("b", "t", "1.0", "MAX"), ("c", "t", "2.0", "AVERAGE")]
    j = make_plan(make_model(["t"], [("p", "0.5", ["t"])], subs)).to_json()
    streams = _by_key(j)
    helper = streams["d.s.t/ALL/1.0"]
    assert (helper["sent"], helper["id"], helper["subscribers"]) == (True, 0, [])
    assert [k for k, s in streams.items() if s["sent"]] == ["d.s.t/ALL/1.0"]
    assert streams["d.s.t/AVERAGE/2.0"]["derived_from"] == "d.s.t/ALL/1.0"
    assert j["subscriptions"]["a"] == "d.s.t/MIN/1.0"
    # 10 samples per window: the aggregates are cheaper, no helper
    j = make_plan(make_model(["t"], [("p", "0.1", ["t"])], subs)).to_json()
    assert "d.s.t/ALL/1.0" not in _by_key(j)


def test_cheapest_cover_average_from_sum_and_count(make_model: Any) -> None:
    subs = [("a", "t", "1.0", "AVERAGE"), ("b", "t", "1.0", "SUM"), ("c", "t", "1.0", "COUNT")]
    j = make_plan(make_model(["t"], [("p", "0.1", ["t"])], subs)).to_json()
    streams = _by_key(j)
    # AVERAGE (4 B + count) is dropped: SUM (4 B) and COUNT (1 B) give it
    assert not streams["d.s.t/AVERAGE/1.0"]["sent"]
    assert [x["key"] for x in streams["d.s.t/AVERAGE/1.0"]["sources"]] == [
        "d.s.t/SUM/1.0",
        "d.s.t/COUNT/1.0",
    ]
    assert streams["d.s.t/SUM/1.0"]["sent"] and streams["d.s.t/COUNT/1.0"]["sent"]


def test_count_derived_from_average(make_model: Any) -> None:
    subs = [("a", "t", "1.0", "AVERAGE"), ("c", "t", "2.0", "COUNT")]
    j = make_plan(make_model(["t"], [("p", "0.1", ["t"])], subs)).to_json()
    assert _by_key(j)["d.s.t/COUNT/2.0"]["derived_from"] == "d.s.t/AVERAGE/1.0"


def test_find_sources_prefers_same_aggregation_and_fewest_windows() -> None:
    t = "d.s.t"
    sent = [
        StreamKey(t, "ALL", Fraction(1, 2)),
        StreamKey(t, "MIN", Fraction(1, 2)),
        StreamKey(t, "MIN", Fraction(1)),
    ]
    (src,) = find_sources(StreamKey(t, "MIN", Fraction(3)), sent) or ()
    assert (src.stream.period, src.factor) == (Fraction(1), 3)
    assert find_sources(StreamKey(t, "MAX", Fraction(3)), sent[1:]) is None
    assert find_sources(StreamKey("d.s.u", "MIN", Fraction(3)), sent) is None
    assert StreamKey.parse("d.s.t/MIN/0.5") == StreamKey(t, "MIN", Fraction(1, 2))
