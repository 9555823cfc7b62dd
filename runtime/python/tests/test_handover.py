"""One grid across a handover (handover.py, docs/fleet.md "The serving station"):
station b takes over a drone whose PubBroker still runs station a's config and adopts
it when its own plan of the same model for a's round trip gives the very same CONFIG;
another model, another CONFIG, another running config, or no fleet: a new CONFIG, as
before. And a datagram run joined while it runs reads 16-bit slot numbers near the
slot a had, not near 0."""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from modd.link import codec
from modd.link.frames import AuthOk, Config, ConfigAck
from modd.subbroker.broker import SubBroker
from modd.subbroker.config import LinkOptions, config_from_model
from modd.subbroker.handover import RunningConfig
from modd.subbroker.linkhooks import Adopted

S1 = Path(__file__).resolve().parents[3] / "metamodel" / "examples" / "scenarios" / "scenario1.modd"
KEY = "modd-test-handover-link-key"
EPOCH = 1_800_000_000 * 10**9


class _Fleet:
    """The fleet record's side a SubBroker reads at handover."""

    def __init__(self, told: list[tuple[str, RunningConfig]]) -> None:
        self.told = told

    def running(self) -> list[tuple[str, RunningConfig]]:
        return self.told

    def others(self) -> list[Any]:
        return []


def _broker(tmp_path: Path, name: str, **changes: Any) -> SubBroker:
    config = config_from_model(
        S1, link=LinkOptions(key="env:MODD_TEST_HANDOVER_KEY"), state_dir=tmp_path / name
    )
    return SubBroker(dataclasses.replace(config, station=name, **changes))


@pytest.fixture
def pair(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[tuple[SubBroker, SubBroker]]:
    monkeypatch.setenv("MODD_TEST_HANDOVER_KEY", KEY)
    a, b = _broker(tmp_path, "a"), _broker(tmp_path, "b")
    yield a, b
    for x in (a, b):
        if x.record is not None:
            x.record.close()


def _serving(a: SubBroker, rtt_s: float = 0.08) -> tuple[Config, dict[str, Any]]:
    """Station a connects to a PubBroker running nothing, sends its CONFIG, gets it
    acked; what a tells the fleet."""
    a.link.stats.rtt_s = rtt_s
    config = a.on_connect(AuthOk(b"", 0, 0), rtt_s)
    assert isinstance(config, Config)
    a.on_config_acked(config, ConfigAck(config.config_id, 0, EPOCH))
    told = a.running_config()
    assert told is not None
    return config, json.loads(json.dumps(told))


def test_the_next_station_adopts_the_config_the_pubbroker_runs(
    pair: tuple[SubBroker, SubBroker],
) -> None:
    a, b = pair
    config, told = _serving(a)
    b.fleet = _Fleet([("a", RunningConfig.from_json({**told, "slot": 70_000}))])  # type: ignore[assignment]
    b.link.stats.rtt_s = 0.5  # b's own round trip would plan otherwise
    got = b.on_connect(AuthOk(b"", config.config_id, EPOCH), 0.5)
    assert isinstance(got, Adopted), got
    assert codec.encode(got.config) == codec.encode(config)
    assert got.ack == ConfigAck(config.config_id, 0, EPOCH) and got.slot == 70_000
    b.on_config_acked(got.config, got.ack)
    assert b._running is not None and b._running.epoch_ns == EPOCH
    # its next CONFIG (a deploy) takes another id than the one that runs
    assert b._prepare(b.config.model, config.config_id, b._meta).config_id != config.config_id


@pytest.mark.parametrize("change", ["model", "config", "epoch", "no fleet"])
def test_anything_else_sends_a_new_config(pair: tuple[SubBroker, SubBroker], change: str) -> None:
    a, b = pair
    config, told = _serving(a)
    ok = AuthOk(b"", config.config_id, EPOCH)
    if change == "model":
        told["model"] = "0" * 64
    elif change == "config":
        told["config"] = told["config"][:-2] + ("00" if told["config"][-2:] != "00" else "01")
    elif change == "epoch":
        ok = AuthOk(b"", config.config_id, EPOCH + 1)
    if change != "no fleet":
        b.fleet = _Fleet([("a", RunningConfig.from_json(told))])  # type: ignore[assignment]
    got = b.on_connect(ok, 0.08)
    assert isinstance(got, Config), got


def test_a_standby_station_tells_no_running_config(pair: tuple[SubBroker, SubBroker]) -> None:
    a, _ = pair
    _serving(a)
    assert "running" not in a._told()  # its link is not up: it serves nothing


def test_a_joined_datagram_run_reads_slot_numbers_near_the_last_one() -> None:
    """Slot 70,003 travels as 70,003 mod 2^16 = 4,467: read near slot 0 it is 4,467, a
    tag that does not verify; near 70,000 it is the slot it was."""
    from modd.link.datagram import DRONE_TO_BASE, DataDatagram, encode_data, session_key
    from modd.link.frames import (
        Aggregation,
        Data,
        StreamSpec,
        TopicSpec,
        Value,
        ValueType,
        value_kind,
    )
    from modd.subbroker.dgruns import RadioCounters, Runs
    from modd.subbroker.linkhooks import SystemClock

    key = session_key(b"psk", bytes(16), bytes(range(16)))
    kinds = [value_kind(ValueType.FLOAT32, Aggregation.AVERAGE)]
    cfg = Config(
        1,
        0,
        (TopicSpec("usv.t.x", ValueType.FLOAT32, 1),),
        (StreamSpec(0, Aggregation.AVERAGE, 250_000),),
    )
    values = codec.encode_data(Data(False, 0, 0, 0, [Value(True, 1.0)]), kinds)[3:]
    raw = encode_data(DataDatagram(1, 70_003, [values]), key, DRONE_TO_BASE)
    for joined, decoded in ((None, False), (70_000, True)):
        runs = Runs(1.0, RadioCounters(), SystemClock())
        runs.accept(cfg, ConfigAck(1, 0, EPOCH), key)
        if joined is not None:
            runs.joined_at(1, joined)
        got = runs.on_datagram(raw)
        assert (got is not None) == decoded
        if got:
            assert got[0][0].slot == 70_003


class _Heard:
    """Diversity's side at takeover: what this station's modem heard."""

    def __init__(self, datagrams: list[bytes]) -> None:
        self.datagrams = datagrams

    def take_heard(self) -> list[bytes]:
        out, self.datagrams = self.datagrams, []
        return out


class _FleetHeard(_Fleet):
    def __init__(self, told: list[tuple[str, RunningConfig]], until: int, held: Any) -> None:
        super().__init__(told)
        self.until, self.held = until, held

    def heard_until(self) -> int:
        return self.until

    def others(self) -> list[Any]:
        return [self.held]


class _Sink:
    def __init__(self) -> None:
        self.values: list[Any] = []

    def put(self, subscriber: str, payload: bytes) -> None:
        from modd.subbroker.payload import DeliveredValue

        self.values.append(DeliveredValue.from_json(payload))


def test_the_next_station_delivers_what_its_modem_heard_under_the_dead_stations_session(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Station a served over udp and died; b's modem heard slots 100..119 (forwarded to
    no one). b adopts a's config and reads them under a's session (its nonces, told by
    the fleet, and the drone's link key): the slots after the last window b heard a
    deliver (104), that verify (112 is forged) and that no station holds (sub_3's
    window of slot 110 is in a's record) are delivered at once and recorded as received."""
    from modd.link.datagram import DRONE_TO_BASE, DataDatagram, encode_data, session_key
    from modd.link.frames import Data, Value
    from modd.subbroker.window_record import WindowRecord

    monkeypatch.setenv("MODD_TEST_HANDOVER_KEY", KEY)
    udp = LinkOptions(key="env:MODD_TEST_HANDOVER_KEY", transport="udp")
    brokers = [
        SubBroker(
            dataclasses.replace(config_from_model(S1, link=udp, state_dir=tmp_path / s), station=s)
        )
        for s in "ab"
    ]
    a, b = brokers
    try:
        nonces = (bytes(range(16)), bytes(range(16, 32)))
        a.link.dgram.nonces = nonces  # type: ignore[attr-defined]
        config, told = _serving(a)
        assert [bytes.fromhex(n) for n in told["session"]] == list(nonces)
        key_a = session_key(KEY.encode(), *nonces)
        kinds = config.kinds()

        def datagram(slot: int, key: bytes = key_a) -> bytes:
            values = [Value(True, float(slot + i)) for i in range(len(kinds))]
            body = codec.encode_data(Data(False, 0, 0, 0, values), kinds)[3:]
            return encode_data(DataDatagram(config.config_id, slot, [body]), key, DRONE_TO_BASE)

        period = 250_000_000
        end = {s: EPOCH + (s + 1) * period for s in range(100, 120)}
        heard = [datagram(s, bytes(32) if s == 112 else key_a) for s in range(100, 120)]
        held = WindowRecord()
        s3 = next(p.stream for p in a._running.plan.streams if "sub_3" in p.subscribers)  # type: ignore[union-attr]
        held.add_filled("sub_3", s3, end[110] - period, end[110])
        running = RunningConfig.from_json({**told, "slot": 100})
        b.fleet = _FleetHeard([("a", running)], end[104], held)  # type: ignore[assignment]
        b.diversity = _Heard(heard)  # type: ignore[assignment]
        b.link.stats.rtt_s = 0.08
        sink = _Sink()
        b._sinks = lambda: [sink]  # type: ignore[method-assign]
        got = b.on_connect(AuthOk(b"", config.config_id, EPOCH), 0.08)
        assert isinstance(got, Adopted), got
        b.on_config_acked(got.config, got.ack)

        ends = {v.end_ns for v in sink.values}
        assert ends, "nothing delivered from what b's modem heard"
        assert min(ends) == end[105] and max(ends) == end[119]
        assert end[112] not in ends  # forged
        at110 = {v.subscriber for v in sink.values if v.end_ns == end[110]}
        at111 = {v.subscriber for v in sink.values if v.end_ns == end[111]}
        assert "sub_3" in at111 and at110 == at111 - {"sub_3"}
        assert all(not v.backfilled for v in sink.values)
        assert b.backfill.record.received[s3].covers(end[105] - period, end[111])
        assert not b.backfill.record.received[s3].covers(end[104] - period, end[104])
        assert b.diversity.take_heard() == []  # type: ignore[union-attr]
    finally:
        for x in brokers:
            if x.record is not None:
                x.record.close()
