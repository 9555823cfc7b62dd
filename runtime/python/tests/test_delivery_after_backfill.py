"""A live window that comes after a backfill delivered it (a NACK's resend that
raced the backfill of the same gap) is not delivered twice; the other
subscribers of the same slot still get theirs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from modd.link.frames import Value
from modd.link.receiver import Window
from modd.link.schedule import SlotIterator
from modd.subbroker.delivery import SlotDelivery
from modd.subbroker.fanout import FanOut
from modd.subbroker.planning import config_for, plan_for
from modd.subbroker.window_record import WindowRecord
from modd_model import load_model
from modd_model.query import topics
from modd_plan.streams import StreamKey

S1 = Path(__file__).resolve().parents[3] / "metamodel" / "examples" / "scenarios" / "scenario1.modd"
EPOCH = 1_795_000_000_000_000_000


class Recorder:
    def __init__(self) -> None:
        self.got: list[str] = []

    def put(self, subscriber: str, payload: bytes) -> None:
        self.got.append(subscriber)


def test_a_window_a_backfill_delivered_is_not_delivered_again_live() -> None:
    model = load_model(S1)
    plan = plan_for(model, None)
    config = config_for(plan, 1)
    info = {t.name: (t.unit, t.type) for t in topics(model).values()}
    periods = [s.period_us for s in config.streams]
    walk = SlotIterator(periods)
    slot = next(walk)
    while len(slot.streams) < 2:  # a slot that completes several subscribers' windows
        slot = next(walk)
    end = EPOCH + slot.offset_us * 1000
    windows = [
        Window(
            config.config_id,
            slot.index,
            sid,
            end - periods[sid] * 1000,
            end,
            Value(True, 1.0, 0, 4),
        )
        for sid in slot.streams
    ]
    asked: list[tuple[str, StreamKey, int, int]] = []

    def nothing_filled(sub: str, s: StreamKey, a: int, b: int) -> bool:
        asked.append((sub, s, a, b))
        return False

    everyone = Recorder()
    n_all = _delivery(plan, config, info).deliver(windows, [everyone], nothing_filled)
    assert n_all >= 2 and len(asked) == n_all and len(everyone.got) == n_all
    # a backfill filled one subscriber's window of this slot before the resend came
    victim, stream, start, end = asked[0]
    record = WindowRecord()
    record.add_filled(victim, stream, start, end)

    def filled(sub: str, s: StreamKey, a: int, b: int) -> bool:
        spans = record.filled.get((sub, s))
        return spans is not None and spans.covers(a, b)

    again = Recorder()
    n = _delivery(plan, config, info).deliver(windows, [again], filled)
    assert n == n_all - 1 and len(again.got) == n_all - 1
    assert sorted([*again.got, victim]) == sorted(everyone.got)


def _delivery(plan: Any, config: Any, info: dict[str, tuple[str, str]]) -> SlotDelivery:
    fan = FanOut([s.stream for s in plan.sent_streams])
    for ps in plan.streams:
        for sub in ps.subscribers:
            fan.route(ps.stream, ps.sources, sub)
    return SlotDelivery(fan, config.config_id, EPOCH, info)


def test_empty_slots_complete_derived_windows_and_deliver_no_sent_window() -> None:
    """An ingest stall over a datagram link: every slot of the first 2 s arrives empty.
    The 2 s derived windows (sub_1, sub_2) are delivered (null, count 0) and told to the
    window record; the 0.25 s subscribers of the sent streams get nothing for them."""
    model = load_model(S1)
    plan = plan_for(model, None)
    config = config_for(plan, 1)
    info = {t.name: (t.unit, t.type) for t in topics(model).values()}
    fan = FanOut([s.stream for s in plan.sent_streams])
    for ps in plan.streams:
        for sub in ps.subscribers:
            fan.route(ps.stream, ps.sources, sub)
    delivery = SlotDelivery(fan, config.config_id, EPOCH, info)
    rec, derived = Recorder(), list[tuple[StreamKey, int, int]]()
    periods = [s.period_us for s in config.streams]
    walk = SlotIterator(periods)
    for _ in range(8):  # the slots of the first 2 s
        slot = next(walk)
        end = EPOCH + slot.offset_us * 1000
        empty = [
            Window(config.config_id, slot.index, sid, end - periods[sid] * 1000, end, Value())
            for sid in slot.streams
        ]
        delivery.deliver(empty, [rec], None, derived.append)
    assert sorted(rec.got) == ["sub_1", "sub_2"]
    assert sorted((s.key, a, b) for s, a, b in derived) == [
        (f"usv.accelerometer.accel_{xy}/AVERAGE/2.0", EPOCH, EPOCH + 2 * 10**9) for xy in "xy"
    ]
