"""The paper's scenarios, loaded from metamodel/examples/scenarios, against expected.json."""

from __future__ import annotations

from fractions import Fraction
from pathlib import Path
from typing import Any

import pytest
from modd_model import load_model
from modd_plan.plan import make_plan


@pytest.mark.parametrize("method", ["exact", "cvxpy"])
def test_scenario1(scenarios_dir: Path, expected: dict[str, Any], method: str) -> None:
    exp = expected["scenario1"]
    plan = make_plan(load_model(scenarios_dir / exp["file"]), method=method)
    j = plan.to_json()
    assert j["buffer_sizes"] == exp["buffer_sizes"]
    assert Fraction(j["hyperperiod_s"]) == Fraction(str(exp["hyperperiod_s"]))
    assert j["messages_per_hyperperiod"] == exp["messages_per_hyperperiod"]
    assert j["infeasible"] == []
    assert j["delays"]["sub_1"] == "0.88" and j["delays"]["sub_3"] == "0.87"
    assert j["delays"]["sub_5"] == "0.01"
    assert [s["date_s"] for s in j["schedule"]["slots"]] == [
        "0.25",
        "0.5",
        "0.75",
        "1.0",
        "1.25",
        "1.5",
        "1.75",
        "2.0",
    ]
    assert all(s["streams"] == [0, 1, 2, 3] for s in j["schedule"]["slots"])


@pytest.mark.parametrize("method", ["exact", "cvxpy"])
def test_scenario2(scenarios_dir: Path, expected: dict[str, Any], method: str) -> None:
    exp = expected["scenario2"]
    plan = make_plan(load_model(scenarios_dir / exp["file"]), method=method)
    j = plan.to_json()
    assert len(j["buffer_sizes"]) == 19
    assert set(j["buffer_sizes"].values()) == {exp["buffer_sizes_all_topics"]}
    assert Fraction(j["hyperperiod_s"]) == Fraction(str(exp["hyperperiod_s"]))
    assert j["messages_per_hyperperiod"] == exp["messages_per_hyperperiod"]
    assert j["schedule"]["slots"] == [{"slot": 0, "date_s": "1.0", "streams": list(range(19))}]
    assert set(j["delays"].values()) == {"0.0"}


def test_scenario1_link_cost(scenarios_dir: Path) -> None:
    link = make_plan(load_model(scenarios_dir / "scenario1.modd")).to_json()[
        "predicted_link_bytes_per_s"
    ]
    # 4 frames/s of 3 B header + 2 x (4 B average + 1 B count) + 2 x 4 B, + 52 B IP/TCP
    assert link["frames_per_s"] == 4.0
    assert link["drone_to_base"] == 4 * (3 + 10 + 8 + 52)
    assert link["base_to_drone"] == 4 * 52
    assert link["plain_pubsub"] > 10 * link["drone_to_base"]
