"""The backfilled mark of a delivered value: absent on live payloads (their bytes
unchanged), true on backfilled ones, exposed by ``modd.subscribe``'s values and
data frames."""

from __future__ import annotations

import pytest
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd.subscriber import to_dataframe


def test_live_payload_unchanged_and_backfilled_marked() -> None:
    live = DeliveredValue("sub_5", "usv.a.z", "MIN", "0.25", "M", 1, 7, 0, 250, -0.5, None, 9)
    head = StreamPayload("usv.a.z", "MIN", "0.25", "M", 1)
    assert subscriber_prefix("sub_5") + head.tail(7, 0, 250, -0.5, None, 9) == live.to_json()
    assert b"backfilled" not in live.to_json()
    back = DeliveredValue("sub_5", "usv.a.z", "MIN", "0.25", "M", 1, 7, 0, 250, -0.5, None, 9, True)
    assert b'"backfilled":true' in back.to_json()
    assert DeliveredValue.from_json(back.to_json()).backfilled
    assert not DeliveredValue.from_json(live.to_json()).backfilled
    df = to_dataframe([live, back])
    assert list(df["backfilled"]) == [False, True]


def test_backfilled_must_be_a_bool() -> None:
    good = DeliveredValue("s", "t", "MIN", "1", "M", 1, 1, 0, 1, 0.0, None, 1).to_dict()
    raw: dict[str, object] = {**good, "backfilled": "yes"}
    with pytest.raises(ValueError, match="backfilled"):
        DeliveredValue.from_dict(raw)
