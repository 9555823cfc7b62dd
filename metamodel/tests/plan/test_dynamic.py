"""Dynamic subscriptions against the scenario 1 plan."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import pytest
from modd_plan.dynamic import Accepted, NotAvailable, check_dynamic
from modd_plan.plan import Plan, make_plan

X = "d.accelerometer.accel_x"
Z = "d.accelerometer.accel_z"


@pytest.fixture
def plan(scenario1_dict: Any) -> Plan:
    return make_plan(scenario1_dict)


def test_accepts_multiples_of_sent_streams(plan: Plan) -> None:
    got = check_dynamic(plan, X, "4", "AVERAGE")
    assert isinstance(got, Accepted)
    assert (got.stream, got.derived_from, got.factor) == (
        f"{X}/AVERAGE/4.0",
        f"{X}/AVERAGE/0.25",
        16,
    )
    same = check_dynamic(plan, Z, Fraction(1, 4), "MIN")
    assert isinstance(same, Accepted) and same.factor == 1
    count = check_dynamic(plan, X, "0.5", "COUNT")  # AVERAGE carries its count
    assert isinstance(count, Accepted) and count.derived_from == f"{X}/AVERAGE/0.25"


def test_refuses_what_cannot_be_computed(plan: Plan) -> None:
    wrong_agg = check_dynamic(plan, Z, "1.0", "AVERAGE")
    assert isinstance(wrong_agg, NotAvailable)
    assert "AVERAGE every 1.0 s needs AVERAGE or ALL" in wrong_agg.reason
    assert "MIN every 0.25 s, MAX every 0.25 s" in wrong_agg.reason
    not_multiple = check_dynamic(plan, Z, "0.3", "MIN")
    assert isinstance(not_multiple, NotAvailable)
    assert "0.3 s is not a whole multiple" in not_multiple.reason
    assert isinstance(check_dynamic(plan, Z, "0.125", "MIN"), NotAvailable)


def test_refuses_bad_requests(plan: Plan) -> None:
    assert "no topic" in _reason(check_dynamic(plan, "d.x.y", "1", "MIN"))
    assert "unknown aggregation" in _reason(check_dynamic(plan, X, "1", "MODE"))
    assert "not a positive decimal" in _reason(check_dynamic(plan, X, "-1", "MIN"))
    assert "not a positive decimal" in _reason(check_dynamic(plan, X, "0", "MIN"))


def test_topic_with_nothing_sent(make_model: Any) -> None:
    model = make_model(["a", "b"], [("p", "0.1", ["a", "b"])], [("s", "a", "1.0", "MIN")])
    reason = _reason(check_dynamic(make_plan(model), "d.s.b", "1", "MIN"))
    assert "nothing of d.s.b is sent" in reason


def _reason(result: Accepted | NotAvailable) -> str:
    assert isinstance(result, NotAvailable)
    return result.reason
