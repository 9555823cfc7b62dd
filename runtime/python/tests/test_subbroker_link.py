"""The SubBroker's link logic through the link session, with no zenoh and no socket:
the SubBroker (broker.py) is the session's handler, as in production, and a
PubBroker written with the protocol's codec and proofs answers. What is checked:
the CONFIG it plans for scenario 1 on connect, the running deployment once
acked, the DATA of each slot delivered to each subscriber with the value sent,
a reconnect that resumes (no CONFIG) or configures again (a fresh id), and the
status document against its contract (schemas/status.schema.json)."""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Iterator
from pathlib import Path

import pytest
from mcap.reader import make_reader
from modd.link import codec
from modd.link.auth import client_proof, server_proof
from modd.link.frames import (
    VERSION,
    Auth,
    AuthOk,
    Challenge,
    Config,
    ConfigAck,
    Data,
    Hello,
    Ping,
    Pong,
    Value,
)
from modd.link.schedule import SlotIterator
from modd.subbroker.broker import SubBroker
from modd.subbroker.config import LinkOptions, config_from_model
from modd.subbroker.status import StatusPublisher
from modd.subbroker.stream_session import StreamSession
from modd_contracts.schema import validate

S1 = Path(__file__).resolve().parents[3] / "metamodel" / "examples" / "scenarios" / "scenario1.modd"
KEY = b"scenario one's link key (32 B)!!"


class Clock:
    def __init__(self) -> None:
        self.now = 50.0

    def monotonic(self) -> float:
        return self.now

    def time_ns(self) -> int:
        return 1_800_000_000 * 10**9 + int(self.now * 1e9)


class Sink:
    """A zenoh delivery that keeps what it is given."""

    def __init__(self) -> None:
        self.got: list[tuple[str, dict[str, object]]] = []

    def put(self, subscriber: str, payload: bytes) -> None:
        self.got.append((subscriber, json.loads(payload)))

    def forget(self, subscriber: str) -> None:
        pass


def _connect(s: StreamSession, running: int = 0, epoch: int = 0) -> list[object]:
    """The handshake, the three PINGs answered; what the session sends after them."""
    s.begin()
    hello = codec.decode(codec.FrameSplitter().feed(b"".join(s.take()))[0])
    assert isinstance(hello, Hello)
    nonce = os.urandom(16)
    s.feed(codec.encode(Challenge(VERSION, nonce)))
    auth = codec.decode(codec.FrameSplitter().feed(b"".join(s.take()))[0])
    assert isinstance(auth, Auth) and auth.mac == client_proof(KEY, hello.nonce, nonce)
    s.feed(codec.encode(AuthOk(server_proof(KEY, hello.nonce, nonce), running, epoch)))
    for _ in range(3):
        (ping,) = [codec.decode(f) for f in codec.FrameSplitter().feed(b"".join(s.take()))]
        assert isinstance(ping, Ping)
        s.feed(codec.encode(Pong(ping.payload)))
    return [codec.decode(f) for f in codec.FrameSplitter().feed(b"".join(s.take()))]


@pytest.fixture
def broker(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[SubBroker]:
    monkeypatch.setenv("MODD_TEST_SUBBROKER_LINK_KEY", KEY.decode())
    config = config_from_model(
        S1, link=LinkOptions(key="env:MODD_TEST_SUBBROKER_LINK_KEY"), state_dir=tmp_path / "state"
    )
    b = SubBroker(config)
    yield b
    if b.record is not None:
        b.record.close()


def _values(config: Config, slot_streams: tuple[int, ...], slot: int) -> list[Value]:
    return [Value(True, float(slot * 10 + sid), 0, 1) for sid in slot_streams]


def test_the_subbroker_configures_runs_and_delivers_each_slot(broker: SubBroker) -> None:
    clock = Clock()
    session = StreamSession(KEY, broker.config.link, broker, lambda: 3.0, clock)
    sink = Sink()
    broker._zenoh = sink  # type: ignore[assignment]
    (config,) = _connect(session, running=1)
    assert isinstance(config, Config) and config.config_id != 1  # never the one it reports
    assert config.config_id == 2 and broker.status()["config_id"] is None
    epoch = clock.time_ns()
    session.feed(codec.encode(ConfigAck(config.config_id, 0, epoch)))
    status = broker.status()
    assert status["config_id"] == config.config_id and status["epoch_ns"] == epoch
    assert validate("status", json.loads(json.dumps(status))) == []
    # every slot of the first two hyperperiods' worth of 40 slots, each value its slot's
    it = SlotIterator([s.period_us for s in config.streams])
    kinds = config.kinds()
    sent: dict[tuple[int, int], float] = {}
    for _ in range(40):
        slot = next(it)
        values = _values(config, slot.streams, slot.index)
        frame = codec.encode_data(
            Data(True, config.config_id, slot.index, slot.index & 0xFF, values),
            [kinds[s] for s in slot.streams],
        )
        session.feed(frame)
        for sid, v in zip(slot.streams, values, strict=True):
            sent[(slot.index, sid)] = v.number
    assert session.stats.data_frames == 40 and session.stats.bad_frames == 0
    running = broker._running
    assert running is not None
    direct = {ps.stream.key: ps.id for ps in running.plan.sent_streams}
    subscribers = sum(len(ps.subscribers) for ps in running.plan.sent_streams)
    delivered = [
        d for _, d in sink.got if f"{d['topic']}/{d['aggregation']}/{d['period_s']}" in direct
    ]
    assert len(delivered) == 40 * subscribers > 0  # every slot, to each subscriber
    # live windows carry no historical mark (the payload's optional ``backfilled``)
    assert not [d for _, d in sink.got if "backfilled" in d]
    for got in delivered:
        stream_id = direct[f"{got['topic']}/{got['aggregation']}/{got['period_s']}"]
        slot_index = got["slot"]
        assert isinstance(slot_index, int) and stream_id is not None
        assert got["value"] == sent[(slot_index, stream_id)], got
        assert got["end_ns"] == epoch + (slot_index + 1) * 250_000_000  # 0.25 s slots
    # the base-station record holds what was delivered, read by the official reader
    assert broker.record is not None
    broker.record.close()
    files = list((broker.config.state_dir or Path()).glob("records/usv/*.mcap"))
    with files[0].open("rb") as f:
        recorded = [json.loads(m.data) for _, _, m in make_reader(f).iter_messages()]
    assert sorted(json.dumps({**r, "delivered_ns": 0}, sort_keys=True) for r in recorded) == sorted(
        json.dumps({**d, "delivered_ns": 0}, sort_keys=True) for _, d in sink.got
    )


def test_a_reconnect_resumes_what_runs_or_configures_again(broker: SubBroker) -> None:
    clock = Clock()
    session = StreamSession(KEY, broker.config.link, broker, lambda: 3.0, clock)
    (config,) = _connect(session)
    assert isinstance(config, Config)
    session.feed(codec.encode(ConfigAck(config.config_id, 0, 77)))
    session.close("link down")
    # the PubBroker still runs it, same epoch: resumed, nothing sent
    assert _connect(session, running=config.config_id, epoch=77) == []
    assert session.stats.state == "up" and broker.status()["config_id"] == config.config_id
    session.close("link down")
    # the PubBroker restarted (another epoch): the same model planned again, a fresh id
    (again,) = _connect(session, running=config.config_id, epoch=78)
    assert isinstance(again, Config) and again.config_id not in (0, config.config_id)
    assert again.streams == config.streams and again.topics == config.topics


class Publisher:
    def __init__(self) -> None:
        self.put_: list[str] = []

    def put(self, payload: str) -> None:
        self.put_.append(payload)


class Session:
    """The zenoh session's one call the status publisher makes."""

    def __init__(self) -> None:
        self.publisher = Publisher()
        self.keys: list[str] = []

    def declare_publisher(self, key: str) -> Publisher:
        self.keys.append(key)
        return self.publisher


def test_the_published_status_holds_the_links_counters(broker: SubBroker) -> None:
    """The whole document on modd/<drone>/status (the snapshot, the byte rates, the
    backpressure) with the session's counters, against its contract."""
    clock = Clock()
    session = StreamSession(KEY, broker.config.link, broker, lambda: 3.0, clock)
    (config,) = _connect(session)
    assert isinstance(config, Config)
    session.feed(codec.encode(ConfigAck(config.config_id, 0, 5)))
    zenoh = Session()
    publisher = StatusPublisher(zenoh, "usv", 60.0, broker.status, lambda: session.stats)  # type: ignore[arg-type]
    publisher.publish_now()
    session.feed(codec.encode(Ping(b"p")))
    status = publisher.publish_now()
    assert zenoh.keys == ["modd/usv/status"] and len(zenoh.publisher.put_) == 2
    published = json.loads(zenoh.publisher.put_[-1])
    assert published == json.loads(json.dumps(status))
    assert validate("status", published) == []
    assert published["bytes_in_per_s"] is not None and published["behind"] is False


def test_the_status_names_its_station_when_it_has_one(tmp_path: Path, broker: SubBroker) -> None:
    """The fleet view's serving station (docs/fleet.md): the status of a SubBroker
    started with a station names it, in the contract; one without says nothing."""
    assert "station" not in broker.status()
    config = dataclasses.replace(broker.config, station="shore", state_dir=tmp_path / "shore")
    stationed = SubBroker(config)
    try:
        status = json.loads(json.dumps(stationed.status()))
        assert status["station"] == "shore"
        assert validate("status", status) == []
        assert validate("status", {**status, "station": 7}) != []
    finally:
        if stationed.record is not None:
            stationed.record.close()
