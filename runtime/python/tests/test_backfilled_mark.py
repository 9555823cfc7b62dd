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


class _Payload:
    def __init__(self, data: bytes) -> None:
        self.data = data

    def to_bytes(self) -> bytes:
        return self.data


class _Sample:
    def __init__(self, value: DeliveredValue) -> None:
        self.payload = _Payload(value.to_json())


class _Session:
    def declare_subscriber(self, key: str, handler: object) -> object:
        return self


def test_latest_is_the_newest_live_value_whatever_comes_late() -> None:
    """``Subscription.latest``: a backfilled window, older or newer, never becomes it;
    a live one newer than it does (each window once: the identity differs)."""
    from modd.subscriber import Subscription

    def win(k: int, value: float, backfilled: bool = False) -> DeliveredValue:
        return DeliveredValue(
            "s", "t", "LAST", "1", "M", 1, k, (k - 1) * 10**9, k * 10**9, value, None, 1,
            backfilled, "usv", 5, k + (1000 if backfilled else 0),
        )  # fmt: skip

    lasts: list[float | None] = []
    sub = Subscription(_Session(), "modd/usv/sub/s", lambda v: None)  # type: ignore[arg-type]
    assert sub.latest is None
    for v in (win(1, 1.0), win(9, 9.0), win(3, -3.0, True), win(12, -12.0, True), win(10, 10.0)):
        sub._receive(_Sample(v))  # type: ignore[arg-type]
        lasts.append(None if sub.latest is None else sub.latest.value)
    assert lasts == [1.0, 9.0, 9.0, 9.0, 10.0]
