"""The SubBroker's fast data path against the slow, obvious one, and its
backpressure report.

- Payloads: ``subscriber_prefix + StreamPayload.tail`` must be byte for byte
  ``DeliveredValue.to_json`` (what every consumer parses), for every kind of value.
- Slots: ``SlotDelivery`` must deliver exactly what the fan-out's outputs turned
  into ``DeliveredValue`` objects one by one give (the SubBroker's former path),
  on a plan with sent and derived streams, for many slots.
- Backpressure: a lag or a receive backlog past its bound turns ``behind`` on,
  logged once; back under half of both turns it off, logged once; the status
  document carries the fields.
"""

from __future__ import annotations

import logging
import math
import random
import time
from fractions import Fraction
from typing import Any, cast

import pytest
from modd.link.frames import Value
from modd.link.receiver import Window
from modd.link.schedule import SlotIterator
from modd.subbroker.backpressure import Backpressure, socket_backlog
from modd.subbroker.delivery import SlotDelivery
from modd.subbroker.fanout import FanOut, period_us
from modd.subbroker.link import LinkStats
from modd.subbroker.payload import DeliveredValue, StreamPayload, subscriber_prefix
from modd.subbroker.planning import config_for, plan_for
from modd.subbroker.status import StatusPublisher
from modd.zenoh_session import ZenohSettings, open_session
from modd_model.query import topics
from modd_plan.windows import split_window, window_of

VALUES: list[Any] = [
    0.0,
    -0.0,
    1.5,
    -123.456e-7,
    1e300,
    3,
    -7,
    0,
    True,
    False,
    None,
    [],
    [1.0, 2.5],
    [1, 2, 3],
    [True, False],
    float("nan"),
    float("inf"),
    float(Fraction(1, 3)),
    2**70,
]


@pytest.mark.parametrize("value", VALUES, ids=repr)
def test_payload_bytes_equal_the_reference_encoding(value: Any) -> None:
    rng = random.Random(repr(value))
    for name in ("sub_1", "dyn_1a2b3c4d", "x"):
        count = rng.choice([None, 0, 17])
        ref = DeliveredValue(
            name,
            "usv.ins.accel_x",
            "AVERAGE",
            "0.25",
            "METER_PER_SECOND_SQUARED",
            200,
            rng.randrange(2**40),
            1_795_241_220_643_782_675,
            1_795_241_220_893_782_675,
            value,
            count,
            time.time_ns(),
        )
        head = StreamPayload(ref.topic, ref.aggregation, ref.period_s, ref.unit, ref.config_id)
        fast = subscriber_prefix(name) + head.tail(
            ref.slot, ref.start_ns, ref.end_ns, cast(Any, ref.value), ref.count, ref.delivered_ns
        )
        assert fast == ref.to_json()
        if not (isinstance(value, float) and not math.isfinite(value)):
            assert DeliveredValue.from_json(fast) == ref


def _model(n_subs: int) -> dict[str, Any]:
    rng = random.Random(5)
    names = [f"v{j}" for j in range(4)]
    types = ["float32", "float64", "int", "bool"]
    return {
        "schemaVersion": "1.0",
        "drone": {
            "name": "d",
            "sensors": [
                {
                    "name": "s",
                    "variables": [
                        {"name": n, "unit": "METER", "type": t}
                        for n, t in zip(names, types, strict=True)
                    ],
                }
            ],
        },
        "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 7171}, "logPath": "/tmp/l"},
        "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 7272}, "configPath": "/tmp/c"},
        "publishers": [{"name": "p", "periodS": "0.05", "topics": [f"d.s.{n}" for n in names]}],
        "subscribers": [
            {
                "name": f"sub{k}",
                "topic": f"d.s.{rng.choice(names)}",
                "periodS": rng.choice(["0.25", "0.5", "1.0", "2.0"]),
                "aggregation": rng.choice(
                    ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "COUNT", "SUM", "ALL"]
                ),
            }
            for k in range(n_subs)
        ],
    }


def _value(rng: random.Random, vtype: str, aggregation: str) -> Value:
    if rng.random() < 0.1:
        return Value(False)
    if aggregation == "ALL":
        samples: list[float | int] = [
            rng.randint(0, 1) if vtype == "bool" else rng.uniform(-5, 5)
            for _ in range(rng.randint(1, 4))
        ]
        return Value(True, samples=samples)
    return Value(
        True,
        rng.uniform(-5, 5),
        rng.randint(-9, 9) if vtype != "bool" else rng.randint(0, 1),
        rng.randint(1, 9),
    )


class Recorder:
    def __init__(self) -> None:
        self.got: list[tuple[str, bytes]] = []

    def put(self, subscriber: str, payload: bytes) -> None:
        self.got.append((subscriber, payload))


def test_slot_delivery_equals_the_value_by_value_path() -> None:
    model = _model(60)
    plan = plan_for(model, None)
    config = config_for(plan, 3)
    epoch = 1_795_000_000_000_000_000
    info = {t.name: (t.unit, t.type) for t in topics(model).values()}
    sent = [s.stream for s in plan.sent_streams]
    fast_fan, ref_fan = FanOut(sent), FanOut(sent)
    for ps in plan.streams:
        for sub in ps.subscribers:
            fast_fan.route(ps.stream, ps.sources, sub)
            ref_fan.route(ps.stream, ps.sources, sub)
    assert any(ps.sources for ps in plan.streams), "the model must exercise derivations"
    fast = SlotDelivery(fast_fan, config.config_id, epoch, info)
    rec, rng = Recorder(), random.Random(9)
    want: list[tuple[str, bytes]] = []
    walk = SlotIterator([s.period_us for s in config.streams])
    periods = [s.period_us for s in config.streams]
    for _ in range(40):
        slot = next(walk)
        end = epoch + slot.offset_us * 1000
        windows = [
            Window(
                config.config_id,
                slot.index,
                sid,
                end - periods[sid] * 1000,
                end,
                _value(rng, info[sent[sid].topic][1], sent[sid].aggregation),
            )
            for sid in slot.streams
        ]
        n = fast.deliver(windows, [rec, rec])
        # the reference: the fan-out's outputs, one DeliveredValue per subscriber
        by_id = {
            w.stream: window_of(w.value, sent[w.stream].aggregation, info[sent[w.stream].topic][1])
            for w in windows
        }
        expected = 0
        for out in ref_fan.on_slot(slot.index, slot.offset_us, by_id):
            value, count = split_window(out.stream.aggregation, out.value)
            for sub in out.subscribers:
                ref = DeliveredValue(
                    sub,
                    out.stream.topic,
                    out.stream.aggregation,
                    out.stream.key.rsplit("/", 1)[1],
                    info[out.stream.topic][0],
                    config.config_id,
                    slot.index,
                    epoch + (slot.offset_us - period_us(out.stream)) * 1000,
                    end,
                    cast(Any, value),  # the contract's type names the JSON escapes too
                    count,
                    0,
                )
                want += [(sub, ref.to_json())] * 2  # two sinks
                expected += 1
        assert n == expected
    assert len(rec.got) == len(want) > 200
    for (name, got), (want_name, ref_bytes) in zip(rec.got, want, strict=True):
        assert name == want_name
        delivered = DeliveredValue.from_json(got)
        assert delivered.delivered_ns > 0
        # delivered_ns is the delivery time: compare everything else byte for byte
        assert (
            DeliveredValue.from_dict({**delivered.to_dict(), "delivered_ns": 0}).to_json()
            == ref_bytes
        )
        assert got.startswith(subscriber_prefix(name))


def test_backpressure_turns_on_and_off_once_each(caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO, logger="modd.subbroker.backpressure")
    bp = Backpressure(behind_lag_s=1.0, behind_backlog_bytes=100_000)
    offset = 3_000_000_000  # the drone's clock 3 s behind the base station's: no matter
    t = 0
    for _ in range(20):  # keeps up: delivered 2 ms after each window's end
        t += 250_000_000
        bp.observe(t, 0, t + offset + 2_000_000)
    assert bp.as_dict()["behind"] is False and bp.as_dict()["lag_s"] == 0.0
    lag = 0
    for _ in range(20):  # falls behind: each slot delivered 100 ms later than the last
        t += 250_000_000
        lag += 100_000_000
        bp.observe(t, 5_000, t + offset + 2_000_000 + lag)
    status = bp.as_dict()
    assert status["behind"] is True and status["lag_s"] == pytest.approx(2.0)
    assert status["behind_episodes"] == 1 and status["max_lag_s"] == pytest.approx(2.0)
    warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
    assert len(warnings) == 1 and "falling behind" in warnings[0].getMessage()
    for _ in range(20):  # catches up: lag back down in 100 ms steps
        t += 250_000_000
        lag = max(0, lag - 100_000_000)
        bp.observe(t, 0, t + offset + 2_000_000 + lag)
    assert bp.as_dict()["behind"] is False and bp.as_dict()["behind_since_ns"] is None
    infos = [r for r in caplog.records if "caught up" in r.getMessage()]
    assert len(infos) == 1
    # a backlog alone is enough, and hysteresis holds it until it halves
    bp.observe(t, 100_001, t + offset + 2_000_000)
    assert bp.behind
    bp.observe(t, 60_000, t + offset + 2_000_000)
    assert bp.behind
    bp.observe(t, 40_000, t + offset + 2_000_000)
    assert not bp.behind and bp.episodes == 2
    bp.observe(t, 0, t + offset + 5 * 10**9)
    assert bp.behind
    bp.reset(t)  # a new link session: measured afresh, not behind
    assert bp.as_dict()["behind"] is False and bp.as_dict()["lag_s"] is None


def test_socket_backlog_counts_unread_bytes() -> None:
    import socket

    a, b = socket.socketpair()
    with a, b:
        assert socket_backlog(b) == 0
        a.sendall(b"x" * 1234)
        deadline = time.monotonic() + 2
        while socket_backlog(b) < 1234 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert socket_backlog(b) == 1234
        b.recv(1000)
        assert socket_backlog(b) == 234
    assert socket_backlog(None) == 0


def test_status_document_reports_backpressure() -> None:
    session = open_session(ZenohSettings(mode="peer"))
    try:
        stats = LinkStats()
        pub = StatusPublisher(session, "usv", 3600, lambda: {"drone": "usv"}, lambda: stats)
        pub.start()
        try:
            doc = pub.publish_now()
            assert doc["behind"] is False and doc["lag_s"] is None
            stats.backpressure.observe(0, 0, 1_000_000)
            stats.backpressure.observe(10**9, 0, 10**9 + 1_000_000 + 3 * 10**9)
            doc = pub.publish_now()
            assert doc["behind"] is True and doc["lag_s"] == 3.0
            assert doc["behind_since_ns"] == 10**9 + 1_000_000 + 3 * 10**9
        finally:
            pub.stop()
    finally:
        session.close()  # type: ignore[no-untyped-call]
