"""Ranged playback in Foxglove: a recorded minute (the PubBroker archive's
shape: one JSON channel per topic) served by the replay server and read by
the @foxglove/ws-protocol client, which seeks to the middle and plays; the
messages that follow start at the seek time, in order, equal to the file's.
The player's pure part (seek, pause, speed) is tested directly."""

from __future__ import annotations

import json
import signal
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any, cast

import httpx2 as httpx
import pytest
from ecosystem_support import node_json
from mcap.writer import Writer
from modd.ports import free_port
from modd_backend.foxglove_replay import Player, Recorded, ReplayServer, load_recording
from pubbroker_harness import BIN, PubBroker, run_load
from served import serve
from viewer_schema import refusals

T0 = 1_795_000_000_000_000_000
TOPICS = ("usv.ctd.temperature", "usv.ctd.conductivity")
SCHEMA = b'{"type":"object","properties":{"value":{"type":"number"}}}'


def value(topic: int, k: int) -> float:
    return round(10.0 * topic + k / 10.0, 3)


def write_archive(path: Path, topics: Sequence[str], n: int) -> Path:
    """``n`` samples at 10 Hz from T0 on each topic, written like the PubBroker's archive."""
    with open(path, "wb") as f:
        w = Writer(f)
        w.start()
        sid = w.register_schema("modd.Sample", "jsonschema", SCHEMA)
        cids = [w.register_channel(t, "json", sid, {"type": "float32"}) for t in topics]
        for k in range(n):
            for i, cid in enumerate(cids):
                t = T0 + k * 100_000_000
                w.add_message(cid, t, json.dumps({"value": value(i, k)}).encode(), t)
        w.finish()  # type: ignore[no-untyped-call]
    return path


@pytest.fixture
def minute(tmp_path: Path) -> Path:
    """A minute at 10 Hz on two topics."""
    return write_archive(tmp_path / "usv-minute.mcap", TOPICS, 600)


@pytest.fixture
def server(minute: Path) -> Iterator[ReplayServer]:
    s = ReplayServer([minute], "127.0.0.1", free_port())
    try:
        yield s
    finally:
        s.stop()


def test_seek_then_play_in_foxglove(server: ReplayServer) -> None:
    seek = T0 + 30_000_000_000
    report = node_json(
        "foxglove_client.cjs", server.url, "4", "--seek", str(seek), "--after", "1", timeout=30
    )
    assert report["protocol"] == "foxglove.sdk.v1" and not report["errors"]
    assert "playbackControl" in report["serverInfo"][
        "capabilities"
    ] or "rangedPlayback" in json.dumps(report["serverInfo"])
    assert {a["topic"] for a in report["advertised"]} == set(TOPICS)
    states = report["playbackStates"]
    assert states and int(states[0]["currentTime"]) == seek
    for i, topic in enumerate(TOPICS):
        msgs = report["messages"][topic]
        times = [int(m["logTime"]) for m in msgs]
        assert times[0] == seek, "playback starts at the seek time"
        assert times == sorted(times)
        ks = [(t - T0) // 100_000_000 for t in times]
        assert ks == list(range(ks[0], ks[0] + len(ks))), "no message skipped"
        assert 10 <= len(ks) <= 45, len(ks)  # about 3 s played at speed 1
        assert [m["msg"]["value"] for m in msgs] == [value(i, k) for k in ks]


def played(path: Path, autoplay: bool, *options: str) -> dict[str, Any]:
    """What a Foxglove client that only subscribes receives in 4 s of a replay."""
    server = ReplayServer([path], "127.0.0.1", free_port(), autoplay=autoplay)
    try:
        report: dict[str, Any] = node_json(
            "foxglove_client.cjs", server.url, "4", *options, timeout=30
        )
    finally:
        server.stop()
    assert not report["errors"], report["errors"]
    return report


@pytest.mark.parametrize("autoplay", [True, False])
def test_autoplay_serves_a_viewer_without_playback_controls(minute: Path, autoplay: bool) -> None:
    # Lichtblick's WebSocket player subscribes and never sends a playback
    # request: with autoplay the range plays from its start; without, nothing.
    report = played(minute, autoplay)
    got = report["messages"]
    if not autoplay:
        assert not any(got.get(t) for t in TOPICS)
        return
    for i, topic in enumerate(TOPICS):
        times = [int(m["logTime"]) for m in got[topic]]
        assert times and times[0] == T0, "played from the start of the range"
        ks = [(t - T0) // 100_000_000 for t in times]
        assert ks == list(range(len(ks))), "in order, none skipped"
        assert [m["msg"]["value"] for m in got[topic]] == [value(i, k) for k in ks]
    # PlaybackState status 0 = Playing (the SDK's PlaybackStatus)
    assert report["playbackStates"] and report["playbackStates"][0]["status"] == 0


def test_autoplay_drops_nothing_of_a_viewer_subscribing_channel_by_channel(tmp_path: Path) -> None:
    """Eleven channels (the demo record's count) subscribed 40 ms apart, as
    Lichtblick's panels do: every channel gets every message of the file, as
    the official ``mcap`` reader reads it (autoplay began on the first
    subscription and lost 0.24-0.40 s of 8 of 11 channels)."""
    from mcap.reader import make_reader

    # 1.5 s at 10 Hz, from the range's very start
    path = write_archive(tmp_path / "eleven.mcap", [f"/usv/sub_{i}" for i in range(11)], 15)
    with open(path, "rb") as f:
        archived: dict[str, list[tuple[int, float]]] = {}
        for _, ch, m in make_reader(f).iter_messages():
            archived.setdefault(ch.topic, []).append((m.log_time, json.loads(m.data)["value"]))
    report = played(path, True, "--subscribe-gap", "40")
    assert len(archived) == 11
    got = {
        t: [(int(m["logTime"]), m["msg"]["value"]) for m in ms]
        for t, ms in report["messages"].items()
    }
    assert {t: len(v) for t, v in got.items()} == {t: len(v) for t, v in archived.items()}
    assert got == archived


def test_a_base_station_record_replays_valid_against_its_schemas(tmp_path: Path) -> None:
    """The SubBroker's record (empty MIN windows, ALL lists, boolean LAST)
    replayed: every message a Foxglove client receives validates against the
    schema advertised for its channel (``jsonschema``), and equals the record's
    window read by the official reader (a null left out, a boolean as 1/0)."""
    from mcap.reader import make_reader
    from modd.subbroker.payload import DeliveredValue
    from modd.subbroker.record import BaseRecord
    from test_viewer_schemas import violations

    rec = BaseRecord(tmp_path / "records", "usv")
    rec.begin("m", T0)
    for k in range(10):
        start, end = T0 + k * 100_000_000, T0 + (k + 1) * 100_000_000
        for name, agg, value, count in (
            ("avg", "AVERAGE", 0.5 * k, 4),
            ("low", "MIN", None if k % 3 else -1.0 * k, None),
            ("all", "ALL", [float(i) for i in range(k % 3)], k % 3),
            ("pump", "LAST", k % 2 == 0, None),
        ):
            rec.put(
                name,
                DeliveredValue(
                    name,
                    f"usv.a.{name}",
                    agg,
                    "0.1",
                    "1",
                    1,
                    k,
                    start,
                    end,
                    cast(Any, value),
                    count,
                    end + 1,
                    backfilled=name == "avg" and k in (3, 4),  # filled after an outage
                ).to_json(),
            )
    rec.close()
    path = next((tmp_path / "records" / "usv").glob("*.mcap"))
    with open(path, "rb") as f:
        recorded: dict[str, list[dict[str, Any]]] = {}
        for _, ch, m in make_reader(f).iter_messages():
            recorded.setdefault(ch.topic, []).append(json.loads(m.data))
    report = played(path, True)
    schemas = {a["topic"]: json.loads(a["schema"]) for a in report["advertised"]}
    got = report["messages"]
    assert set(got) == set(recorded) and len(recorded) == 4
    for topic, msgs in got.items():
        assert not refusals(schemas[topic]), topic
        for m in msgs:
            assert violations(schemas[topic], m["msg"]) == [], (topic, m["msg"])
        # every window carries its historical mark (a live one false, which the record leaves out)
        want = [
            {k: (int(v) if isinstance(v, bool) else v) for k, v in d.items() if v is not None}
            | {"backfilled": d.get("backfilled") is True}
            for d in recorded[topic]
        ]
        assert [m["msg"]["backfilled"] for m in msgs] == [
            topic.endswith("/avg") and k in (3, 4) for k in range(10)
        ], topic
        # JSON numbers are doubles in the client: ns times agree to the microsecond
        assert [
            {k: pytest.approx(v, abs=1000) if k.endswith("_ns") else v for k, v in m["msg"].items()}
            for m in msgs
        ] == want, topic


def test_player_seek_pause_speed() -> None:
    msgs = [Recorded(t, "a", b"{}") for t in range(0, 10_000_000_000, 1_000_000_000)]
    p = Player(msgs)
    assert p.advance(5.0) == []  # paused at start
    p.control(True, 1.0, 3_000_000_000)
    assert [m.log_time for m in p.advance(1.0)] == [3_000_000_000, 4_000_000_000]
    p.control(False, 1.0, None)
    assert p.advance(3.0) == []
    p.control(True, 2.0, None)
    assert [m.log_time for m in p.advance(1.0)] == [5_000_000_000, 6_000_000_000]
    p.control(True, 1.0, -5)  # clamped to the start
    assert p.advance(0.0)[0].log_time == 0
    p.control(True, 100.0, None)
    assert len(p.advance(1.0)) == 9 and p.ended and not p.playing


def test_a_pubbroker_archive_loads_for_replay(tmp_path: Path) -> None:
    if not BIN.exists():  # make test builds it: missing is a setup bug, not a skip
        pytest.fail(f"{BIN} is missing: run make build")
    b = PubBroker(tmp_path, [(t, "float32") for t in TOPICS])
    b.start()
    try:
        load = run_load(f"unix:{b.unix_path}", list(TOPICS), 100.0, 0.5)
    finally:
        assert b.stop(signal.SIGTERM) == 0
    channels, messages = load_recording(sorted(b.archive_dir.glob("*.mcap")))
    assert set(channels) == set(TOPICS) and len(messages) == load.published
    assert channels[TOPICS[0]].encoding == "json"
    broken = tmp_path / "cut.mcap"
    broken.write_bytes(next(b.archive_dir.glob("*.mcap")).read_bytes()[:-200])
    with pytest.raises(ValueError, match="modd archive recover"):
        load_recording([broken])


def test_the_workbench_replays_an_archive_in_foxglove(tmp_path: Path, minute: Path) -> None:
    """Archives panel > Replay in Foxglove: the backend serves the chosen
    range of a drone's archive — here a file still being written (no summary,
    cut mid-record) — at its ``/foxglove/replay`` (the URL it answers carries
    a single-use ticket); Foxglove seeks and plays it."""
    import io

    from fastapi.testclient import TestClient
    from modd_backend.app import create_app
    from modd_backend.settings import Settings

    folder = tmp_path / "archives" / "usv"
    folder.mkdir(parents=True)
    data = minute.read_bytes()
    (folder / "writing.mcap").write_bytes(data[: len(data) * 2 // 3])  # no summary, cut
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password="pw-12345678",
        archive_dir=tmp_path / "archives",
        foxglove_replay_port=free_port(),
    )
    with serve(settings) as base:
        url = f"{base}/api/drones/usv/archives/writing.mcap/replay"
        assert httpx.post(url, json={}).status_code == 401
        token = httpx.post(
            f"{base}/api/auth/login", json={"username": "admin", "password": "pw-12345678"}
        ).json()["token"]
        auth = {"Authorization": f"Bearer {token}"}
        assert (
            httpx.post(
                f"{base}/api/drones/usv/archives/..%2Fx.mcap/replay", json={}, headers=auth
            ).status_code
            == 404
        )
        r = httpx.post(url, json={"start_ns": T0 + 70_000_000_000}, headers=auth, timeout=30)
        assert r.status_code == 422 and "no message in that range" in r.json()["detail"], r.text
        assert str(folder) not in r.text
        r = httpx.post(url, json={"start_ns": T0 + 10_000_000_000}, headers=auth, timeout=30)
        assert r.status_code == 200, r.text
        info = r.json()
        assert info["url"].startswith(f"ws://{base[7:]}/foxglove/replay?ticket=")
        assert info["topics"] == sorted(TOPICS)
        assert info["start_ns"] == T0 + 10_000_000_000
        assert httpx.get(f"{base}/api/replay", headers=auth).json()["file"] == "writing.mcap"

        seek = T0 + 20_000_000_000
        report = node_json(
            "foxglove_client.cjs", info["url"], "3", "--seek", str(seek), "--after", "1", timeout=30
        )
        assert not report["errors"] and int(report["playbackStates"][0]["currentTime"]) == seek
        for i, topic in enumerate(TOPICS):
            msgs = report["messages"][topic]
            ks = [(int(m["logTime"]) - T0) // 100_000_000 for m in msgs]
            assert ks[0] == 200 and ks == list(range(200, 200 + len(ks))), ks[:5]
            assert [m["msg"]["value"] for m in msgs] == [value(i, k) for k in ks]
        # the cut: nothing past the file's last complete record is played
        assert info["end_ns"] < T0 + 60_000_000_000
        # the ticket is spent: the same URL opens nothing now
        again = node_json("foxglove_client.cjs", info["url"], "1", timeout=30)
        assert not again["messages"] and again["protocol"] in (None, "")

        # "play at once": a viewer that only subscribes gets the range from its start
        r = httpx.post(
            url, json={"start_ns": T0 + 10_000_000_000, "autoplay": True}, headers=auth, timeout=30
        )
        assert r.status_code == 200 and r.json()["autoplay"] is True, r.text
        report = node_json("foxglove_client.cjs", r.json()["url"], "2", timeout=30)
        ks = [(int(m["logTime"]) - T0) // 100_000_000 for m in report["messages"][TOPICS[0]]]
        assert ks[:1] == [100] and ks == list(range(100, 100 + len(ks))), ks[:5]

        assert httpx.delete(f"{base}/api/replay", headers=auth).status_code == 204
        assert httpx.get(f"{base}/api/replay", headers=auth).json() is None

    off = Settings(
        data_dir=tmp_path / "data2",
        zenoh_enabled=False,
        initial_admin_password="pw-12345678",
        archive_dir=tmp_path / "archives",
    )
    with TestClient(create_app(off, out=io.StringIO()), base_url="http://127.0.0.1") as c:
        token = c.post(
            "/api/auth/login", json={"username": "admin", "password": "pw-12345678"}
        ).json()["token"]
        r = c.post(
            "/api/drones/usv/archives/writing.mcap/replay",
            json={},
            headers={"Authorization": f"Bearer {token}"},
        )
        assert r.status_code == 409 and "--foxglove-replay-port" in r.json()["detail"]


def test_the_base_station_record_replays_through_the_same_server(
    tmp_path: Path, minute: Path
) -> None:
    """Archives panel, base-station records: the record of what was delivered
    plays on the same replay server as the drone's archives (seek and play)."""

    from modd_backend.settings import Settings

    folder = tmp_path / "records" / "usv"
    folder.mkdir(parents=True)
    (folder / "usv-mission.mcap").write_bytes(minute.read_bytes())
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password="pw-12345678",
        record_dir=tmp_path / "records",
        foxglove_replay_port=free_port(),
    )
    with serve(settings) as base:
        url = f"{base}/api/drones/usv/records/usv-mission.mcap/replay"
        token = httpx.post(
            f"{base}/api/auth/login", json={"username": "admin", "password": "pw-12345678"}
        ).json()["token"]
        auth = {"Authorization": f"Bearer {token}"}
        assert httpx.post(url, json={}).status_code == 401
        assert (
            httpx.post(
                f"{base}/api/drones/usv/records/nothing.mcap/replay", json={}, headers=auth
            ).status_code
            == 404
        )
        r = httpx.post(url, json={}, headers=auth, timeout=30)
        assert r.status_code == 200, r.text
        info = r.json()
        assert info["file"] == "usv-mission.mcap" and info["topics"] == sorted(TOPICS)
        assert info["messages"] == 1200 and info["start_ns"] == T0
        seek = T0 + 45_000_000_000
        report = node_json(
            "foxglove_client.cjs", info["url"], "2", "--seek", str(seek), "--after", "1", timeout=30
        )
        assert not report["errors"] and int(report["playbackStates"][0]["currentTime"]) == seek
        times = [int(m["logTime"]) for m in report["messages"][TOPICS[0]]]
        assert times and times[0] == seek and times == sorted(times)
