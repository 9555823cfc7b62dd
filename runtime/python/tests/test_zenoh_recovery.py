"""Asking again for delivered values zenoh's recovery gave up on (modd.zenoh_recovery):
a reader's advanced subscriber asks a publisher's cache once for what it missed; an ask
that goes unanswered (right after a partition heals) leaves a jump in that publisher's
numbers. The reader asks that cache again and delivers each value once. Oracle: the
values the publisher put, in one in-process zenoh session (no network: a peer that
listens on nothing and scouts nothing)."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest
import zenoh
from modd import zenoh_recovery
from modd.zenoh_recovery import _AskAgain, values_publisher

KEY = "modd/usv/sub/sub_3"


@pytest.fixture
def session() -> Any:
    conf = zenoh.Config()
    conf.insert_json5("mode", '"peer"')
    conf.insert_json5("scouting/multicast/enabled", "false")
    conf.insert_json5("listen/endpoints", "[]")
    s = zenoh.open(conf)
    yield s
    s.close()  # type: ignore[no-untyped-call]


def _put(session: Any, n: int) -> tuple[list[zenoh.Sample], Any]:
    """n values through the SubBroker's advanced publisher (returned: its cache lives as
    long as it does), as a plain reader got them."""
    got: list[zenoh.Sample] = []
    sub = session.declare_subscriber(KEY, got.append)
    pub = values_publisher(
        session, KEY, zenoh.Encoding.APPLICATION_JSON, zenoh.CongestionControl.BLOCK
    )
    for i in range(n):
        pub.put(f"v{i}")
    deadline = time.monotonic() + 5
    while len(got) < n and time.monotonic() < deadline:
        time.sleep(0.01)
    sub.undeclare()
    assert len(got) == n
    return got, pub


def _values(samples: list[zenoh.Sample]) -> list[str]:
    return [s.payload.to_string() for s in samples]


def test_a_jump_is_asked_for_again_and_each_value_comes_once(
    session: Any, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(zenoh_recovery, "ASK_AGAIN_S", (0.05, 0.1))
    put, _pub = _put(session, 10)
    out: list[zenoh.Sample] = []
    done = threading.Event()

    def deliver(s: zenoh.Sample) -> None:
        out.append(s)
        if len(out) == 10:
            done.set()

    again = _AskAgain(session, deliver)
    for i in (0, 1, 2, 7, 8, 5, 9):  # 3..6 given up; 5 a copy that came late anyway
        again.on_sample(put[i])
    assert done.wait(5), _values(out)
    time.sleep(0.3)  # nothing more comes
    assert sorted(_values(out), key=lambda v: int(v[1:])) == [f"v{i}" for i in range(10)]
    assert len(out) == 10
    again.on_sample(put[4])  # a copy after all
    assert len(out) == 10
    again.close()


def test_what_the_cache_no_longer_holds_is_given_up_once(
    session: Any, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    monkeypatch.setattr(zenoh_recovery, "ASK_AGAIN_S", (0.05, 0.05))
    put, _pub = _put(session, 5)
    out: list[zenoh.Sample] = []
    again = _AskAgain(session, out.append)
    again.on_sample(put[0])
    # a jump of 5,000: more than the cache keeps, and none of it there
    info = put[4].source_info
    assert info is not None
    forged = _with_sn(put[4], info, 5004)
    with caplog.at_level("WARNING", logger="modd.zenoh_recovery"):
        again.on_sample(forged)
        deadline = time.monotonic() + 5
        while "could not be had again" not in caplog.text and time.monotonic() < deadline:
            time.sleep(0.02)
    assert f"{zenoh_recovery.CACHE_SAMPLES} values of {KEY}" in caplog.text
    assert _values(out) == ["v0", "v4"]
    again.close()


def _with_sn(sample: zenoh.Sample, info: Any, sn: int) -> Any:
    """``sample`` as if its publisher had numbered it ``sn``."""

    class Numbered:
        payload = sample.payload
        key_expr = sample.key_expr
        source_info = zenoh.SourceInfo(info.source_id, sn)

    return Numbered()


@pytest.mark.parametrize("heard_late", [True, False])
def test_a_publisher_first_heard_past_its_start_is_asked_for_its_first_values(
    session: Any, monkeypatch: pytest.MonkeyPatch, heard_late: bool
) -> None:
    """A publisher began while this reader was cut off (a station took a drone over while
    the reader's router was down): its first value heard is number 4, long after the
    reader subscribed; 0..3 are asked for. Heard at once after subscribing, it is a
    publisher that was there before the reader: nothing is asked."""
    monkeypatch.setattr(zenoh_recovery, "ASK_AGAIN_S", (0.05, 0.1))
    monkeypatch.setattr(zenoh_recovery, "NEW_SOURCE_AFTER_S", 0.0 if heard_late else 60.0)
    put, _pub = _put(session, 6)
    out: list[zenoh.Sample] = []
    again = _AskAgain(session, out.append)
    time.sleep(0.01)
    again.on_sample(put[4])
    again.on_sample(put[5])
    time.sleep(0.6)
    want = ["v4", "v5", "v0", "v1", "v2", "v3"] if heard_late else ["v4", "v5"]
    assert _values(out) == want
    again.close()
