"""The plan JSON (shared contract) and the infeasible case."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from fractions import Fraction
from typing import Any

from modd_plan.plan import make_plan

CONTRACT_KEYS = {
    "hyperperiod_s",
    "messages_per_hyperperiod",
    "topics",
    "streams",
    "subscriptions",
    "buffer_sizes",
    "schedule",
    "delays",
    "predicted_link_bytes_per_s",
    "infeasible",
    "constants",
}


def test_contract_fields(scenario1_dict: Any) -> None:
    j = make_plan(scenario1_dict).to_json()
    assert set(j) >= CONTRACT_KEYS
    json.dumps(j)  # serialisable as it is
    assert isinstance(j["hyperperiod_s"], str) and isinstance(j["messages_per_hyperperiod"], int)
    assert j["topics"][2] == {
        "id": 2,
        "name": "d.accelerometer.accel_z",
        "type": "float32",
        "unit": "NONE",
        "publication_period_s": "0.04",
        "period_us": 40000,
        "buffer_size": 6,
    }
    stream = j["streams"][0]
    assert set(stream) >= {
        "id",
        "key",
        "topic",
        "aggregation",
        "period_s",
        "period_us",
        "sent",
        "derived_from",
        "factor",
        "subscribers",
    }
    assert j["schedule"]["streams"][3] == {
        "id": 3,
        "key": "d.accelerometer.accel_z/MAX/0.25",
        "period_us": 250000,
    }
    assert {"drone_to_base", "base_to_drone", "plain_pubsub"} <= set(
        j["predicted_link_bytes_per_s"]
    )
    assert j["constants"] == {
        "max_buffer": 1000,
        "ping_s": "0.83",
        "alpha": "1.0",
        "beta": "1.0",
        "delay_cap_s": "2.49",
    }


def test_infeasible_names_topics_and_subscribers_and_keeps_the_uncapped_plan(
    make_model: Any,
) -> None:
    subs = [("fast", "a", "0.25", "MIN"), ("slow", "a", "8.0", "MIN"), ("ok", "b", "1.0", "MAX")]
    model = make_model(["a", "b"], [("p", "0.05", ["a", "b"])], subs)
    j = make_plan(model).to_json()
    assert j["violates_delay_cap"] is True
    (bad,) = j["infeasible"]
    assert bad["topic"] == "d.s.a" and bad["subscribers"] == ["fast", "slow"]
    assert "0.25 s (fast) to 8.0 s (slow)" in bad["reason"]
    assert "3 x PING = 2.49 s" in bad["reason"]
    # the uncapped optimum: n x 0.05 at the middle, 4.125 s -> n = 82 (4.1 s)
    assert j["buffer_sizes"] == {"d.s.a": 82, "d.s.b": 20}
    assert j["delays"]["slow"] == "3.9"
    relaxed = make_plan(model, ping_s=make_plan(model).constants.ping_s * 2).to_json()
    assert relaxed["infeasible"] == [] and relaxed["buffer_sizes"] == j["buffer_sizes"]


def test_the_cap_is_lifted_only_for_the_offending_topic(make_model: Any) -> None:
    subs = [
        ("fast", "a", "0.25", "MIN"),
        ("slow", "a", "8.0", "MIN"),
        ("c1", "c", "0.25", "MIN"),
        ("c2", "c", "0.25", "MAX"),
        ("c3", "c", "5.0", "MIN"),
    ]
    j = make_plan(make_model(["a", "c"], [("p", "0.05", ["a", "c"])], subs)).to_json()
    assert [x["topic"] for x in j["infeasible"]] == ["d.s.a"]
    # uncapped, c would follow its median (n = 22, c3 waits 3.9 s); capped at
    # 2.49 s its best is n = 51 (2.55 s): delays 2.3, 2.3, 2.45
    assert j["buffer_sizes"]["d.s.c"] == 51
    assert [j["delays"][s] for s in ("c1", "c2", "c3")] == ["2.3", "2.3", "2.45"]


def test_publication_period_too_long_for_the_cap(make_model: Any) -> None:
    model = make_model(["a"], [("p", "10.0", ["a"])], [("s", "a", "1.0", "MIN")])
    (bad,) = make_plan(model).to_json()["infeasible"]
    assert "publication period of 10.0 s" in bad["reason"] and "n = 1" in bad["reason"]


def test_unpublished_and_unsubscribed_topics(make_model: Any) -> None:
    model = make_model(
        ["a", "b", "c"],
        [("p", "0.1", ["a", "b"])],
        [("s", "a", "1.0", "MIN"), ("t", "c", "1.0", "MIN")],
    )
    j = make_plan(model).to_json()
    assert j["buffer_sizes"] == {"d.s.a": 10, "d.s.b": 1}  # b: nobody asks, smallest n
    assert j["topics"][2]["buffer_size"] is None
    assert j["infeasible"] == [
        {"topic": "d.s.c", "subscribers": ["t"], "reason": "no publisher publishes this topic"}
    ]


def test_overrides_change_the_constants(scenario1_dict: Any) -> None:
    plan = make_plan(scenario1_dict, max_buffer=20, alpha=Fraction(0), beta=Fraction(2))
    assert plan.constants.max_buffer == 20
    assert plan.buffer_sizes["d.accelerometer.accel_x"] == 20
    assert plan.buffer_sizes["d.accelerometer.accel_z"] == 6


def test_slot_listing_is_capped(make_model: Any) -> None:
    names = [f"v{i}" for i in range(30)]
    subs = [(f"s{i}", v, "0.25", "MIN") for i, v in enumerate(names)]
    subs.append(("slow", "v0", "1000.0", "MAX"))  # 4000 slots per hyperperiod
    sched = make_plan(make_model(names, [("p", "0.05", names)], subs)).to_json()["schedule"]
    assert sched["slots_truncated"] is True
    assert sched["slots_listed"] == 666  # 666 x 30 ids <= 20,000 < 667 x 30
    assert len(sched["streams"]) == 31


def test_no_subscribers(make_model: Any) -> None:
    j = make_plan(make_model(["a"], [("p", "0.1", ["a"])], [])).to_json()
    assert (j["hyperperiod_s"], j["messages_per_hyperperiod"]) == ("0.0", 0)
    assert j["schedule"]["slots"] == [] and j["buffer_sizes"] == {"d.s.a": 1}


_HASH_SCRIPT = """
import json, random, sys
from modd_plan.plan import make_plan
rng = random.Random(4)
names = [f"v{i}" for i in range(8)]
aggs = ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "ALL", "COUNT", "SUM"]
subs = [{"name": f"s{k}", "topic": "d.s." + rng.choice(names),
         "periodS": rng.choice(["0.25", "0.5", "1.0", "1.5", "3.0"]),
         "aggregation": rng.choice(aggs)} for k in range(40)]
model = {"schemaVersion": "1.0",
         "drone": {"name": "d", "sensors": [{"name": "s", "variables": [
             {"name": n, "unit": "NONE"} for n in names]}]},
         "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 1}, "logPath": "/l"},
         "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 2}, "configPath": "/c"},
         "publishers": [{"name": "p", "periodS": "0.05", "topics": ["d.s." + n for n in names]}],
         "subscribers": subs}
json.dump(make_plan(model).to_json(), sys.stdout, sort_keys=True)
"""


def test_plan_does_not_depend_on_the_hash_seed() -> None:
    outputs = {
        subprocess.run(
            [sys.executable, "-c", _HASH_SCRIPT],
            capture_output=True,
            text=True,
            check=True,
            env={**os.environ, "PYTHONHASHSEED": seed},
        ).stdout
        for seed in ("1", "2")
    }
    assert len(outputs) == 1 and json.loads(outputs.pop())["streams"]
