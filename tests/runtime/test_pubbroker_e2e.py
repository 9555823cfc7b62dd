"""The real modd-pubbroker under the paper's loads: the base station (Python codec) receives
DATA, the archive is read with the official `mcap` reader, and every window is recomputed
from the archive (the oracle)."""

from __future__ import annotations

import signal
import subprocess
import threading
import time
from typing import Any

from modd.link.frames import Aggregation, Config, StreamSpec
from pubbroker_harness import (
    BIN,
    BaseStation,
    f32,
    hand_config_scenario1,
    read_archive,
    run_load,
    scenario_config,
    signal_value,
)


def test_help() -> None:
    out = subprocess.run([str(BIN), "--help"], capture_output=True, text=True, timeout=10)
    assert out.returncode == 0 and "--config" in out.stdout
    bad = subprocess.run([str(BIN)], capture_output=True, text=True, timeout=10)
    assert bad.returncode == 2


def test_bad_config_file_is_named(tmp_path: Any) -> None:
    p = tmp_path / "c.json"
    p.write_text(
        '{"link": {"key": "env:X"}, "ingress": {"port": 1}, "archive": {"dir": "/tmp/x"},'
        ' "topics": [{"name": "a", "type": "float16"}]}'
    )
    out = subprocess.run([str(BIN), "--config", str(p)], capture_output=True, text=True, timeout=10)
    assert out.returncode == 1
    assert f"{p}: /topics/0/type" in out.stderr


def _run_scenario(broker_factory: Any, n: int, seconds: float) -> None:
    from pubbroker_harness import check_windows

    config = scenario_config(n)
    names = [t.name for t in config.topics]
    b = broker_factory([(t, "float32") for t in names])
    base = BaseStation(b.link_port)
    ack = base.configure(config)
    assert ack.status == 0 and ack.config_id == 1
    base.start()
    load = run_load(f"unix:{b.unix_path}", names, 25.0, seconds)
    time.sleep(max(s.period_us for s in config.streams) / 1e6 + 0.3)  # last windows close
    got = base.snapshot()
    base.close()
    assert b.stop() == 0
    archive = read_archive(b.archive_dir)
    # Everything published is archived, with the publisher's timestamp and value.
    assert {t: len(v) for t, v in archive.items()} == load.per_topic
    for i, t in enumerate(names):
        assert [a.value for a in archive[t]] == [signal_value(i, k) for k in range(len(archive[t]))]
        stamps = [a.log_time for a in archive[t]]
        assert stamps == sorted(stamps)
    checked = check_windows(got.windows, {1: config}, archive)
    per_slot = len(config.streams) if n == 1 else len(config.streams)
    assert checked >= per_slot * (seconds / (config.streams[0].period_us / 1e6) - 2)
    # STATUS rode along: counters agree with the archive.
    assert got.statuses, "no STATUS received"
    last = got.statuses[-1]
    assert last["samples_in"] <= load.published
    assert last["rejected_unknown_topic"] == 0 and last["config_id"] == 1


def test_scenario1_end_to_end(broker_factory: Any) -> None:
    _run_scenario(broker_factory, 1, 4.0)


def test_scenario2_end_to_end(broker_factory: Any) -> None:
    _run_scenario(broker_factory, 2, 4.0)


def test_hand_built_scenario1_config_matches_the_planner() -> None:
    assert scenario_config(1) == hand_config_scenario1()


def test_bad_input_is_counted_never_archived(broker_factory: Any) -> None:

    from modd.link.frames import ValueType
    from modd.publisher import connect, encode_hello, encode_register, encode_samples

    b = broker_factory()
    base = BaseStation(b.link_port)
    base.configure(hand_config_scenario1())
    base.start()
    x, z = "usv.accelerometer.accel_x", "usv.accelerometer.accel_z"
    s = connect(f"tcp:127.0.0.1:{b.tcp_port}")
    types = [ValueType.FLOAT32, ValueType.FLOAT32, ValueType.FLOAT64]
    t0 = time.time_ns()
    s.sendall(
        encode_hello("bad")
        + encode_register(0, ValueType.FLOAT32, x)
        + encode_register(1, ValueType.FLOAT32, "usv.nope")
        + encode_register(2, ValueType.FLOAT64, z)
        + encode_samples(
            [
                (0, t0, 1.5),
                (0, t0 + 1, float("nan")),
                (0, t0 - 5, 2.0),
                (1, t0, 1.0),
                (2, t0, 1.0),
                (0, t0 + 2, float("inf")),
                (0, t0 + 3, 2.5),
            ],
            types,
        )
    )
    # A corrupt frame: the broker counts it, drops this publisher, keeps serving the others.
    s.sendall(bytes([0x05, 0x03, 0x05, 0x00, 0x01, 0x02]))
    s.settimeout(5)
    while s.recv(65536):  # the broker's answers (catalogue), then the close
        pass
    s.close()
    good = run_load(f"unix:{b.unix_path}", [x], 25.0, 1.2)
    time.sleep(1.2)
    got = base.snapshot()
    base.close()
    assert b.stop() == 0
    st = got.statuses[-1]
    assert st["rejected_not_finite"] == 2
    assert st["rejected_timestamp"] == 0  # 5 ns older than the previous: accepted (out of order)
    assert st["rejected_unknown_topic"] == 1
    assert st["rejected_wrong_type"] == 1
    assert st["ingress_malformed_frames"] == 1
    assert st["rejected_malformed"] == 0  # the bad frame announced no decodable record
    archive = read_archive(b.archive_dir)
    assert [a.value for a in archive[x][:3]] == [1.5, 2.0, 2.5]
    assert len(archive[x]) == 3 + good.published
    assert "usv.nope" not in archive and z not in archive
    assert st["samples_in"] == 7 + good.published or st["samples_in"] <= 7 + good.published
    assert "malformed frame" in b.log()


def test_peer_without_the_key_is_rejected_and_the_broker_keeps_serving(broker_factory: Any) -> None:
    import socket

    import pytest
    from modd.link.frames import ProtocolError

    b = broker_factory()
    with pytest.raises(ProtocolError, match="AUTH_FAILED"):
        BaseStation(b.link_port, key=b"wrong-key")
    # Garbage before the handshake: an ERROR frame and a closed connection.
    with socket.create_connection(("127.0.0.1", b.link_port), timeout=2) as s:
        s.sendall(b"GET / HTTP/1.1\r\n\r\n")
        data = s.recv(1024)
        assert data and data[1] == 0x7F
    # A peer that says nothing is timed out.
    with socket.create_connection(("127.0.0.1", b.link_port), timeout=5) as s:
        t = time.monotonic()
        while s.recv(1024):
            pass
        assert time.monotonic() - t < 4.5
    base = BaseStation(b.link_port)
    assert base.configure(hand_config_scenario1()).status == 0
    base.ping(b"\x01\x02")
    base.start()
    deadline = time.monotonic() + 2
    while not base.snapshot().pongs and time.monotonic() < deadline:
        time.sleep(0.01)
    assert base.snapshot().pongs == [b"\x01\x02"]
    base.close()
    assert b.alive()
    log = b.log()
    assert "peer rejected" in log and "HMAC" in log


def test_config_switch_at_a_slot_boundary_and_reconnect(broker_factory: Any) -> None:
    from pubbroker_harness import check_windows

    b = broker_factory()
    names = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
    c1 = hand_config_scenario1(config_id=1)
    c2 = Config(
        2,
        1,
        c1.topics,
        (
            StreamSpec(0, Aggregation.COUNT, 100000),
            StreamSpec(1, Aggregation.SUM, 300000),
            StreamSpec(2, Aggregation.LAST, 500000),
            StreamSpec(2, Aggregation.FIRST, 500000),
            StreamSpec(1, Aggregation.ALL, 200000),
        ),
    )
    base = BaseStation(b.link_port)
    ack1 = base.configure(c1)
    base.start()
    stop = threading.Event()
    result: dict[str, Any] = {}

    def load() -> None:
        result["load"] = run_load(f"unix:{b.unix_path}", names, 25.0, 5.0, stop=stop)

    th = threading.Thread(target=load)
    th.start()
    time.sleep(1.1)
    ack2 = base.configure(c2)
    assert ack2.status == 0
    assert (ack2.epoch_ns - ack1.epoch_ns) % 250_000_000 == 0  # a slot boundary of config 1
    time.sleep(1.0)
    # The base station goes away and comes back: AUTH_OK names the running config.
    first = base.snapshot()
    base.close()
    time.sleep(0.5)
    base = BaseStation(b.link_port)
    assert base.auth_ok.config_id == 2 and base.auth_ok.epoch_ns == ack2.epoch_ns
    base.resume(c2)
    base.start()
    th.join()
    time.sleep(0.8)
    second = base.snapshot()
    base.close()
    assert b.stop() == 0
    archive = read_archive(b.archive_dir)
    assert sum(len(v) for v in archive.values()) == result["load"].published
    configs = {1: c1, 2: c2}
    n = check_windows(first.windows, configs, archive)
    n += check_windows(second.windows, configs, archive)
    assert {w.config_id for w in first.windows} == {1, 2}
    # While no base station was connected, slots were dropped and counted, not queued.
    assert second.statuses and second.statuses[-1]["frames_dropped"] >= 1
    assert "counters: uptime_s=" in b.log()
    # No sample counted twice or lost at the switch: COUNT windows of config 2 plus the last
    # config-1 AVERAGE window of accel_x cover the samples around the switch exactly.
    switch = ack2.epoch_ns
    before = [w for w in first.windows if w.config_id == 1 and w.stream == 0 and w.end_ns == switch]
    after = [
        w for w in first.windows if w.config_id == 2 and w.stream == 0 and w.start_ns == switch
    ]
    assert before and after
    xs = [a.log_time for a in archive[names[0]]]
    assert before[0].value.count == sum(switch - 250_000_000 <= t < switch for t in xs)
    assert after[0].value.count == sum(switch <= t < switch + 100_000_000 for t in xs)
    assert n > 20


def test_sigterm_flushes_everything_and_closes_the_file(broker_factory: Any) -> None:
    from mcap.reader import make_reader

    b = broker_factory(archive={"flush_interval_ms": 60000})  # only SIGTERM flushes
    names = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
    load = run_load(f"tcp:127.0.0.1:{b.tcp_port}", names, 200.0, 0.5)
    time.sleep(0.2)
    assert b.stop(signal.SIGTERM) == 0
    archive = read_archive(b.archive_dir)
    assert sum(len(v) for v in archive.values()) == load.published
    (path,) = list(b.archive_dir.glob("*.mcap"))
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
        assert summary is not None and summary.statistics is not None
        assert summary.statistics.message_count == load.published
        assert {c.topic for c in summary.channels.values()} == set(names)
    assert "stopped:" in b.log()


def test_archive_rotates_and_every_file_reads_back(broker_factory: Any) -> None:
    b = broker_factory(archive={"rotate_bytes": 3000, "chunk_bytes": 1000, "compression": "lz4"})
    names = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
    load = run_load(f"unix:{b.unix_path}", names, 300.0, 1.0)
    assert b.stop() == 0
    files = list(b.archive_dir.glob("*.mcap"))
    assert len(files) > 2
    archive = read_archive(b.archive_dir)
    assert sum(len(v) for v in archive.values()) == load.published
    assert archive[names[0]][0].value == f32(signal_value(0, 0))


def test_kill9_loses_at_most_the_flush_interval(broker_factory: Any) -> None:
    from pubbroker_harness import read_archive_records

    b = broker_factory(archive={"flush_interval_ms": 200})
    names = [f"usv.accelerometer.accel_{a}" for a in "xyz"]
    load = run_load(f"unix:{b.unix_path}", names, 100.0, 1.5)
    time.sleep(0.6)  # > flush interval: everything handed over has been written
    b.stop(signal.SIGKILL)
    archive = read_archive_records(b.archive_dir)
    assert sum(len(v) for v in archive.values()) == load.published


def test_a_flooding_publisher_does_not_stall_the_others(broker_factory: Any) -> None:
    from modd.link.codec import varint
    from modd.link.frames import ValueType
    from modd.publisher import connect, encode_hello, encode_register
    from pubbroker_harness import check_windows

    b = broker_factory()
    config = hand_config_scenario1()
    names = [t.name for t in config.topics]
    base = BaseStation(b.link_port)
    base.configure(config)
    base.start()
    stop = threading.Event()
    flooded = [0]

    def flood() -> None:
        s = connect(f"unix:{b.unix_path}")
        s.sendall(encode_hello("flood") + encode_register(0, ValueType.FLOAT32, "usv.flood"))
        records = bytes(13 * 4096)  # local id 0, timestamp 0, value 0.0: all valid, all equal
        body = bytes([0x03]) + varint(4096) + records
        frame = varint(len(body)) + body
        while not stop.is_set():
            s.sendall(frame)
            flooded[0] += 4096
        s.close()

    th = threading.Thread(target=flood)
    th.start()
    try:
        load = run_load(f"unix:{b.unix_path}", names, 25.0, 3.0)
    finally:
        stop.set()
        th.join()
    time.sleep(0.6)
    got = base.snapshot()
    base.close()
    assert b.stop() == 0
    archive = read_archive(b.archive_dir)
    assert {t: len(v) for t, v in archive.items()} == load.per_topic
    assert check_windows(got.windows, {1: config}, archive) >= 4 * 10
    assert got.statuses and got.statuses[-1]["rejected_unknown_topic"] > 0
    assert flooded[0] > 100_000
