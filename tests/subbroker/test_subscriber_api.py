"""The Python subscriber API over a real zenoh session: values put on a
subscriber key in the documented payload come out of the iterator, the
callback and the DataFrame; malformed ones are skipped; dynamic requests
treat silence as failure."""

from __future__ import annotations

import json
import threading
import time
from typing import Any

import modd
import pytest
import zenoh
from modd.subbroker.client import NoReply
from modd.subbroker.payload import DeliveredValue
from modd.subscriber import subscribe_dynamic
from modd.zenoh_auth import acl
from modd.zenoh_session import ZenohSettings, client_settings, open_session, wait_connected
from subbroker_harness import free_port, shared_credentials


def value(i: int, sub: str = "sub_1") -> DeliveredValue:
    return DeliveredValue(
        sub,
        "usv.a.x",
        "AVERAGE",
        "0.25",
        "METER",
        1,
        i,
        i * 250_000_000,
        (i + 1) * 250_000_000,
        0.5 * i,
        6,
        10**18 + i,
    )


@pytest.fixture
def pair() -> Any:
    port = free_port()
    server = open_session(ZenohSettings(listen=(f"tcp/127.0.0.1:{port}",)))
    yield server, port
    server.close()  # type: ignore[no-untyped-call]


def test_iterate_collect_dataframe_and_callback(pair: Any) -> None:
    server, port = pair
    sub = modd.subscribe("usv", "sub_1", connect=f"tcp/127.0.0.1:{port}")
    seen: list[DeliveredValue] = []
    cb = modd.subscribe("usv", "sub_1", seen.append, connect=f"tcp/127.0.0.1:{port}")
    time.sleep(0.3)
    for i in range(5):
        server.put("modd/usv/sub/sub_1", value(i).to_json())
    server.put("modd/usv/sub/sub_1", b"{not json")
    server.put("modd/usv/sub/sub_2", value(9, "sub_2").to_json())  # another key: not seen
    first = sub.get(timeout_s=2)
    assert first == value(0)
    it = iter(sub)
    assert next(it) == value(1)
    df = sub.dataframe(count=3, duration_s=2)
    assert list(df["slot"]) == [2, 3, 4] and list(df["value"]) == [1.0, 1.5, 2.0]
    assert str(df["end"].dt.tz) == "UTC" and df["end"].iloc[0].value == 750_000_000
    assert sub.get(timeout_s=0.2) is None and sub.malformed == 1
    deadline = time.monotonic() + 2
    while len(seen) < 5 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert seen == [value(i) for i in range(5)]
    done = threading.Event()

    def drain() -> None:
        list(sub)  # ends when the subscription closes
        done.set()

    threading.Thread(target=drain, daemon=True).start()
    sub.close()
    cb.close()
    assert done.wait(2)
    with pytest.raises(ValueError):
        sub.collect()


def test_dynamic_without_subbroker_is_no_reply() -> None:
    """A router with no SubBroker behind it: no reply, said as such."""
    port = free_port()
    router = open_session(
        ZenohSettings(
            mode="router",
            listen=(f"tcp/127.0.0.1:{port}",),
            access_control=acl(None),
            dictionary_file=str(shared_credentials().dictionary),
        )
    )
    session = open_session(
        client_settings(f"tcp/127.0.0.1:{port}", shared_credentials().cred_file("backend"))
    )
    try:
        assert wait_connected(session, 2.0)
        with pytest.raises(NoReply):
            subscribe_dynamic("usv", "usv.a.x", "1.0", "MIN", session=session, timeout_s=1)
    finally:
        session.close()  # type: ignore[no-untyped-call]
        router.close()  # type: ignore[no-untyped-call]


def test_nothing_listening_is_a_clear_error() -> None:
    """A client session fails at once, naming where it tried, when nothing listens."""
    where = f"tcp/127.0.0.1:{free_port()}"
    with pytest.raises(ValueError, match=f"cannot open a zenoh session \\(client, {where}\\)"):
        open_session(client_settings(where))


def test_a_malformed_value_is_dropped_alone_and_the_rest_is_kept(pair: Any) -> None:
    """Wrong types, over-deep JSON and a raising callback cost only themselves
    (issue 23: one wrong value made dataframe() raise and lose everything)."""
    server, port = pair
    sub = modd.subscribe("usv", "sub_1", connect=f"tcp/127.0.0.1:{port}")
    calls: list[int] = []

    def fragile(v: DeliveredValue) -> None:
        calls.append(v.slot)
        if v.slot == 1:
            raise RuntimeError("a bug in the user's callback")

    cb = modd.subscribe("usv", "sub_1", fragile, connect=f"tcp/127.0.0.1:{port}")
    time.sleep(0.3)
    good = value(0).to_dict()
    bad = [
        {**good, "value": "3.5"},  # a string where a number goes
        {**good, "value": {"x": 1}},
        {**good, "start_ns": "soon"},
        {**good, "count": 2.5},
        {**good, "slot": True},
    ]

    def put(payload: str | bytes) -> None:
        # blocking, not zenoh's default of dropping when a queue is full: the
        # 200 KB value, put in a burst to two sessions, was once dropped for one
        server.put("modd/usv/sub/sub_1", payload, congestion_control=zenoh.CongestionControl.BLOCK)

    put(value(0).to_json())
    for b in bad:
        put(json.dumps(b))
    put(b'{"value":' + b"[" * 100_000 + b"]" * 100_000 + b"}")
    for i in (1, 2):
        put(value(i).to_json())
    df = sub.dataframe(count=3, duration_s=3)
    assert list(df["slot"]) == [0, 1, 2] and list(df["value"]) == [0.0, 0.5, 1.0]
    assert sub.malformed == len(bad) + 1
    deadline = time.monotonic() + 15  # a loaded machine schedules zenoh's thread late
    while len(calls) < 3 and time.monotonic() < deadline:
        time.sleep(0.01)
    assert calls == [0, 1, 2]  # the callback's exception stopped nothing
    sub.close()
    cb.close()
    with pytest.raises(ValueError, match="nested deeper than 8 levels at byte 16"):
        DeliveredValue.from_json(b'{"value":' + b"[" * 9 + b"]" * 9 + b"}")
