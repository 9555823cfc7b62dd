"""Several base stations, one zenoh router mesh (docs/fleet.md), as real processes on
loopback (127.0.0.1, ports picked free; no network namespaces yet): station routers
(``python -m modd.station``) that join each other with the ``station`` credentials and
access control, SubBrokers that join their station's router as clients, the C++
PubBroker fed by the load generator, subscribers at each station.

- the mesh: a value put at one station reaches the subscribers of the others once
  each, across a station killed and restarted; a router without the campaign's
  station credentials gets nothing;
- the serving station: one drone heard by two stations is served by one; when that
  station dies (SubBroker and router, kill -9) the other serves it within 10 s, on the
  config the PubBroker runs (adopted: one epoch across the handover), and when it
  comes back it stands by. Every window reaches each subscriber at most once
  (by its identity: drone, subscriber, epoch, window) and equals the aggregate
  recomputed from the drone's archive with the official ``mcap`` reader.
"""

from __future__ import annotations

import shutil
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))

from modd.subbroker.client import request as client_request  # noqa: E402
from modd.subbroker.payload import DeliveredValue  # noqa: E402
from modd.zenoh_auth import CredentialStore  # noqa: E402
from modd.zenoh_recovery import values_subscriber  # noqa: E402
from modd.zenoh_session import ZenohSettings, open_session, wait_connected  # noqa: E402
from subbroker_harness import (  # noqa: E402
    PUBBROKER,
    PYTHON,
    SUBBROKER,
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    read_archive,
    start_load,
    start_pubbroker,
    wait_port,
)

#: The issue's bound: a dead station's drones are served by another within it.
TAKEOVER_S = 10.0


def campaign_credentials(tmp: Path, stations: str) -> dict[str, Path]:
    """One credentials directory per station, copies of the first's: the campaign's
    identities and its one ``station.cred`` (docs/fleet.md, "Credentials")."""
    first = CredentialStore(tmp / f"cred-{stations[0]}").ensure_station()
    dirs = {stations[0]: first.dir}
    for s in stations[1:]:
        d = tmp / f"cred-{s}"
        shutil.copytree(first.dir, d)
        dirs[s] = d
    return dirs


class Station:
    """One station's router (a process), its zenoh id and port."""

    def __init__(self, tmp: Path, name: str, zid: str, cred: Path) -> None:
        self.tmp, self.name, self.zid, self.cred = tmp, name, zid, cred
        self.port = free_port()
        self.peers: dict[str, str] = {}
        self.proc: Proc | None = None

    @property
    def endpoint(self) -> str:
        return f"tcp/127.0.0.1:{self.port}"

    def start(self, tag: str = "") -> Proc:
        peers = [a for zid, ep in self.peers.items() for a in ("--peer", f"{zid}={ep}")]
        cmd = [str(PYTHON), "-m", "modd.station", "--listen", self.endpoint]
        cmd += ["--credentials", str(self.cred), "--id", self.zid, *peers]
        self.proc = Proc(f"router-{self.name}{tag}", cmd, self.tmp / f"router-{self.name}.log")
        wait_port(self.port)
        return self.proc


def mesh(tmp: Path, names: str) -> dict[str, Station]:
    creds = campaign_credentials(tmp, names)
    stations = {n: Station(tmp, n, f"{i + 1:x}{i + 1:x}", creds[n]) for i, n in enumerate(names)}
    for s in stations.values():
        s.peers = {o.zid: o.endpoint for o in stations.values() if o is not s}
    return stations


class Listener:
    """A viewer at one station: every value under modd/*/sub/*, raw and parsed."""

    def __init__(self, station: Station, key: str = "modd/*/sub/*") -> None:
        creds = CredentialStore(station.cred).credentials("viewer")
        settings = ZenohSettings(mode="client", connect=(station.endpoint,), credentials=creds)
        self.session = open_session(settings)
        assert wait_connected(self.session, 5)
        self.raw: list[bytes] = []
        self._lock = threading.Lock()
        # as the subscriber API: what a break kept from it (its station's router down)
        # is asked for again (modd.zenoh_recovery)
        self._sub = values_subscriber(self.session, key, self._on)

    def _on(self, sample: Any) -> None:
        with self._lock:
            self.raw.append(sample.payload.to_bytes())

    def values(self) -> list[DeliveredValue]:
        with self._lock:
            return [DeliveredValue.from_json(r) for r in self.raw if r.startswith(b"{")]

    def close(self) -> None:
        self.session.close()  # type: ignore[no-untyped-call]


@pytest.fixture
def procs() -> Iterator[list[Proc | Listener]]:
    started: list[Proc | Listener] = []
    yield started
    for p in reversed(started):
        if isinstance(p, Listener):
            p.close()
        else:
            p.stop()


def test_three_stations_one_mesh_each_value_once(
    tmp_path: Path, procs: list[Proc | Listener]
) -> None:
    stations = mesh(tmp_path, "abc")
    for s in stations.values():
        procs.append(s.start())
    a, b, c = stations.values()
    creds = CredentialStore(a.cred).credentials("subbroker")
    pub = open_session(ZenohSettings(mode="client", connect=(a.endpoint,), credentials=creds))
    listeners = {s.name: Listener(s) for s in (b, c)}
    procs.extend(listeners.values())
    outsider = Station(tmp_path, "x", "ff", CredentialStore(tmp_path / "cred-x").ensure().dir)
    outsider.peers = {a.zid: a.endpoint}
    procs.append(outsider.start())  # its station.cred is its own: a refuses it
    procs.append(x_listener := Listener(outsider))
    time.sleep(1.5)  # the routers' links, the subscriptions' declarations

    def burst(tag: str, n: int = 100) -> None:
        for i in range(n):
            pub.put("modd/usv/sub/probe", f"{tag}{i}")
            time.sleep(0.002)
        time.sleep(1.0)

    def got(listener: Listener, tag: str) -> list[bytes]:
        return [r for r in listener.raw if r.startswith(tag.encode())]

    try:
        burst("p")
        for listener in listeners.values():
            assert sorted(got(listener, "p")) == sorted(f"p{i}".encode() for i in range(100))
        assert x_listener.raw == [], "a router without the campaign's station credentials"
        assert b.proc is not None
        b.proc.kill9()  # station b dies: a and c go on
        burst("k")
        assert len(got(listeners["c"], "k")) == 100
        procs.append(b.start("-again"))
        time.sleep(2.0)  # b's viewer comes back by itself and subscribes again
        burst("r")
        for listener in listeners.values():
            assert sorted(got(listener, "r")) == sorted(f"r{i}".encode() for i in range(100))
    finally:
        pub.close()  # type: ignore[no-untyped-call]


def subbroker_toml(
    tmp: Path, model: Path, link: int, station: Station, transport: str = "tcp", state: str = ""
) -> Path:
    """Station ``station``'s SubBroker of the drone whose link is 127.0.0.1:``link``
    (``state``: its state directory, none when "")."""
    path = tmp / f"sb-{station.name}.toml"
    state_dir = f'state_dir = "{state}"' if state else ""
    path.write_text(f"""model = "{model}"
station = "{station.name}"
{state_dir}
[link]
transport = "{transport}"
endpoint = "127.0.0.1:{link}"
key = "env:MODD_LINK_KEY"
[zenoh]
mode = "client"
listen = []
connect = ["{station.endpoint}"]
credentials_dir = "{station.cred}"
[delivery]
tcp = false
status_period_s = 0.5
""")
    return path


def start_subbroker(tmp: Path, config: Path, tag: str) -> Proc:
    return Proc(tag, [*SUBBROKER, "--config", str(config)], tmp / f"{tag}.log", dumps_stacks=True)


def identities(values: list[DeliveredValue]) -> list[tuple[Any, ...]]:
    return [(v.drone, v.subscriber, v.epoch_ns, v.window) for v in values]


def first_after(listener: Listener, t_ns: int, timeout_s: float) -> float | None:
    """Seconds from t_ns to the first value whose window ended after it."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        fresh = [v.delivered_ns for v in listener.values() if v.end_ns > t_ns]
        if fresh:
            return (min(fresh) - t_ns) / 1e9
        time.sleep(0.05)
    return None


@pytest.mark.timeout(150)
def test_a_drone_heard_by_two_stations_is_served_once_and_taken_over(
    tmp_path: Path, procs: list[Proc | Listener]
) -> None:
    assert PUBBROKER.exists(), f"{PUBBROKER} is not built: run make build"
    stations = mesh(tmp_path, "ab")
    for s in stations.values():
        procs.append(s.start())
    a, b = stations["a"], stations["b"]
    link, ingress = free_port(), free_port()
    model = model_copy(tmp_path, "scenario1.modd")
    procs.append(start_pubbroker(tmp_path, model, link, ingress))
    procs.append(load := start_load(tmp_path, model, ingress, 45))
    at = {s.name: Listener(s, "modd/usv/sub/*") for s in (a, b)}
    procs.extend(at.values())
    sb = {s.name: subbroker_toml(tmp_path, model, link, s) for s in (a, b)}
    procs.append(sb_a := start_subbroker(tmp_path, sb["a"], "sb-a"))
    assert sb_a.wait_log("station a serves usv", 15), sb_a.log()
    procs.append(sb_b := start_subbroker(tmp_path, sb["b"], "sb-b"))
    time.sleep(6)  # b stands by while a serves
    assert "serves usv" not in sb_b.log(), sb_b.log()
    before = len(at["b"].values())
    assert before > 20, "values of station a reach the subscriber at station b"
    sb_a.kill9()  # station a dies: its SubBroker and its router
    assert a.proc is not None
    a.proc.kill9()
    killed_ns = time.time_ns()
    assert sb_b.wait_log("station b serves usv", TAKEOVER_S), sb_b.log()
    # the PubBroker still runs a's config: b adopts it (one grid, nothing new sent)
    assert sb_b.wait_log("adopting config", 5), sb_b.log()
    back = first_after(at["b"], killed_ns, TAKEOVER_S)
    assert back is not None and back <= TAKEOVER_S, (back, sb_b.log())
    procs.append(a.start("-again"))
    procs.append(sb_a2 := start_subbroker(tmp_path, sb["a"], "sb-a-again"))
    time.sleep(4)
    assert sb_a2.log().count("serves usv") == 0, "a back stands by: b serves"
    # the handover's gap: b fills what no station holds (it heard a's windows delivered)
    job = backfill(b, {"op": "start", "subscriber": "sub_5", "gaps": True})
    assert sb_b.wait_log(f"backfill {job['id']} for sub_5: DONE", 30), sb_b.log()
    load.p.wait(60)
    time.sleep(1.5)
    archive = read_archive(tmp_path / "archive", model)
    for name, listener in at.items():
        values = listener.values()
        ids = identities(values)
        assert all(i[0] == "usv" and i[2] and i[3] is not None for i in ids), ids[:3]
        dup = len(ids) - len(set(ids))
        assert dup == 0, f"{dup} windows twice at station {name}"
        assert check_against_archive({name: values}, archive) > 50
    sub5 = [v for v in at["b"].values() if v.subscriber == "sub_5"]
    filled = sum(v.backfilled for v in sub5)
    assert filled > 0, "the handover's gap was filled"
    assert_every_window(sub5, epochs=1)  # one grid across the handover
    print(f"takeover: first value at b {back:.2f} s after station a was killed; {filled} filled")


def backfill(
    station: Station, request: dict[str, Any], expect: str | tuple[str, ...] = "RUNNING"
) -> dict[str, Any]:
    creds = CredentialStore(station.cred).credentials("backend")
    settings = ZenohSettings(mode="client", connect=(station.endpoint,), credentials=creds)
    session = open_session(settings)
    try:
        assert wait_connected(session, 5)
        reply = client_request(session, "modd/usv/backfill", request)
    finally:
        session.close()  # type: ignore[no-untyped-call]
    assert reply.get("status") in ((expect,) if isinstance(expect, str) else expect), reply
    return reply


def assert_every_window(values: list[DeliveredValue], epochs: int) -> None:
    """Per epoch, every window from the first received to the epoch's last, once."""
    by_epoch: dict[int, list[int]] = {}
    for v in values:
        assert v.epoch_ns is not None and v.window is not None
        by_epoch.setdefault(v.epoch_ns, []).append(v.window)
    assert len(by_epoch) == epochs, sorted(by_epoch)
    for epoch, windows in by_epoch.items():
        missing = sorted(set(range(min(windows), max(windows) + 1)) - set(windows))
        assert not missing, f"epoch {epoch}: windows {missing[:10]} missing"
