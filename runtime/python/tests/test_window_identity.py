"""A delivered window names itself (drone, subscriber, epoch_ns, window): docs/fleet.md.
The fast path (StreamPayload) and the record (DeliveredValue) write the same bytes, the
identity round-trips, and a payload without it (an older SubBroker's) still reads."""

from __future__ import annotations

import json

import pytest
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix, window_index
from modd_contracts.schema import validate

EPOCH = 1_700_000_000_000_000_000
PERIOD = 250_000_000


def test_the_fast_path_writes_the_identity_as_the_record_does() -> None:
    start = EPOCH + 7 * PERIOD
    head = StreamPayload("usv.a.z", "MIN", "0.25", "METER", 3, ("usv", EPOCH, PERIOD))
    fast = subscriber_prefix("sub_5") + head.tail(9, start, start + PERIOD, -0.5, None, 1)
    ref = DeliveredValue(
        "sub_5", "usv.a.z", "MIN", "0.25", "METER", 3, 9, start, start + PERIOD, -0.5, None, 1,
        False, "usv", EPOCH, 7,
    )  # fmt: skip
    assert fast == ref.to_json()
    doc = json.loads(fast)
    assert (doc["drone"], doc["epoch_ns"], doc["window"]) == ("usv", EPOCH, 7)
    assert validate("delivered_value", doc) == []
    assert DeliveredValue.from_json(fast) == ref


def test_a_payload_without_identity_reads_and_writes_as_before() -> None:
    head = StreamPayload("usv.a.z", "MIN", "0.25", "METER", 1)
    line = subscriber_prefix("s") + head.tail(7, 0, PERIOD, 1.5, None, 0)
    assert b"drone" not in line
    assert DeliveredValue.from_json(line).to_json() == line


def test_a_mistyped_identity_is_refused_with_its_field() -> None:
    line = json.loads(
        subscriber_prefix("s")
        + StreamPayload("u.a.z", "MIN", "1", "M", 1).tail(1, 0, 1, 1, None, 0)
    )
    with pytest.raises(ValueError, match="window is '3', not an integer"):
        DeliveredValue.from_dict({**line, "window": "3"})
    with pytest.raises(ValueError, match="drone is 5"):
        DeliveredValue.from_dict({**line, "drone": 5})


def test_the_window_index_is_on_the_configs_grid() -> None:
    assert window_index(EPOCH, EPOCH, PERIOD) == 0
    assert window_index(EPOCH + 3 * PERIOD, EPOCH, PERIOD) == 3
    assert window_index(EPOCH - PERIOD, EPOCH, PERIOD) == -1
