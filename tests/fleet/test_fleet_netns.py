"""A campaign in network namespaces (issue 44, docs/fleet.md): three stations (a, b, c)
and six drones, each in its own namespace made by this test, joined by veth links
(tests/support/netns.py). The addresses (10.44.<link>.1/.2, one /30 per link) and the
fixed ports inside a drone's namespace (7000 link, 7001 ingress) exist only inside those
namespaces, which the test deletes; nothing is added to the host's own namespace.

Stations a, b, c: a router each (``python -m modd.station``, full mesh over the links
a–b, b–c, a–c) and the SubBrokers of the drones it hears (clients of its router, with
``station`` set). Drones: the C++ PubBroker fed by the load generator, linked to the
stations of ``HEARD_BY`` (usv1 to a and b, usv6 to b and c, the others to one). Viewers
at a and at c, in their stations' namespaces (tests/fleet/ns_listener.py).

The scenario: usv1 starts heard by a only; it moves to b (its link to a cut, to b
opened); station b (router and SubBrokers) is killed with -9 and restarted (c takes
usv6 over, usv2 waits for b); the a–b link is cut and healed. Then each drone's serving
station fills its gaps (``modd backfill --gaps``). At each viewer, through the subscriber
API, every window of every drone came exactly once (by identity: drone, subscriber,
epoch, window), equals the aggregate recomputed from that drone's archive with the
official ``mcap`` reader, and every epoch's windows are there from its first to its
last. On the wire (the raw samples) no window comes twice either: b's windows delivered
just before its kill are in its window journal (docs/fleet.md, "Exactly once").
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import subbroker_harness as h  # noqa: E402
from fleet.test_fleet import campaign_credentials  # noqa: E402
from modd.subbroker.payload import DeliveredValue  # noqa: E402
from modd_model.query import topics  # noqa: E402
from support.netns import Fabric, needs_netns  # noqa: E402

pytestmark = needs_netns  # e2e: every test under tests/ (conftest.py CROSS_PROCESS)

STATIONS = "abc"
#: drone -> the stations whose namespaces it is linked to
HEARD_BY = {"usv1": "ab", "usv2": "b", "usv3": "c", "usv4": "a", "usv5": "c", "usv6": "bc"}
LOAD_S = 75
LOADGEN = Path(__file__).resolve().parents[1] / "subbroker" / "loadgen.py"


class Campaign:
    """The namespaces, links and processes of the scenario."""

    def __init__(
        self,
        tmp: Path,
        fabric: Fabric,
        heard_by: dict[str, str] | None = None,
        load_s: float = LOAD_S,
    ) -> None:
        """``heard_by``: the drones in namespaces of their own, and the stations each is
        linked to (``HEARD_BY``); ``load_s``: their load's seconds."""
        self.tmp, self.fabric, self.load_s = tmp, fabric, load_s
        heard_by = HEARD_BY if heard_by is None else heard_by
        self.procs: list[h.Proc] = []
        self.creds = campaign_credentials(tmp, STATIONS)
        self.port = {s: h.free_port() for s in STATIONS}
        self.addr: dict[tuple[str, str], str] = {}  # (whose, seen from) -> address
        for i, s in enumerate(STATIONS):
            for o in STATIONS[i + 1 :]:
                self._link(s, o)
        for drone, heard in heard_by.items():
            for s in heard:
                self._link(drone, s)
        self.models: dict[str, Path] = {}
        self.sb: dict[tuple[str, str], h.Proc] = {}
        self.routers: dict[str, h.Proc] = {}

    def _link(self, x: str, y: str) -> None:
        ax, ay = self.fabric.link(x, y)
        self.addr[(x, y)], self.addr[(y, x)] = ax, ay

    def run(self, name: str, where: str, cmd: list[str]) -> h.Proc:
        proc = h.Proc(name, [*self.fabric.prefix(where), *cmd], self.tmp / f"{name}.log")
        self.procs.append(proc)
        return proc

    def start_router(self, s: str, tag: str = "") -> None:
        zid = {n: f"{i + 1:x}{i + 1:x}" for i, n in enumerate(STATIONS)}
        cmd = [str(h.PYTHON), "-m", "modd.station", "--listen", f"tcp/0.0.0.0:{self.port[s]}"]
        cmd += ["--credentials", str(self.creds[s]), "--id", zid[s]]
        for o in STATIONS:
            if o != s:
                cmd += ["--peer", f"{zid[o]}=tcp/{self.addr[(o, s)]}:{self.port[o]}"]
        self.routers[s] = self.run(f"router-{s}{tag}", s, cmd)
        self.fabric.wait_port(s, "127.0.0.1", self.port[s])

    def start_drone(
        self,
        drone: str,
        seed: int,
        where: str = "",
        ports: tuple[int, int] = (7000, 7001),
        transport: str = "tcp",
    ) -> None:
        """The drone's PubBroker (link on 0.0.0.0:7000 in its namespace, its own
        archive) and its load (ingress 127.0.0.1:7001, in the same namespace); with
        ``where``, in that (station's) namespace instead, on 127.0.0.1:``ports``, without
        a load (the caller feeds it); ``transport``: its link's (udp: on 127.0.0.1, behind
        the radio the caller starts in its namespace)."""
        home = self.tmp / drone
        home.mkdir()
        model: Path = h.model_copy(home, "scenario1.modd")
        doc = json.loads(model.read_text().replace('"usv.', f'"{drone}.'))  # topics
        doc["drone"]["name"] = drone
        model.write_text(json.dumps(doc))
        self.models[drone] = model
        host = "127.0.0.1" if where or transport != "tcp" else "0.0.0.0"
        link = {"transport": transport, "host": host, "port": ports[0], "key": "env:MODD_LINK_KEY"}
        cfg = {
            "name": drone,
            "link": link,
            "ingress": {"host": "127.0.0.1", "port": ports[1]},
            "archive": {"dir": str(home / "archive"), "flush_interval_ms": 200},
            "topics": [{"name": t.name, "type": t.type} for t in topics(doc).values()],
            "status_period_s": 60,
        }
        (home / "pb.json").write_text(json.dumps(cfg))
        pb = [str(h.PUBBROKER), "--config", str(home / "pb.json")]
        self.run(f"pb-{drone}", where or drone, pb)
        self.fabric.wait_port(where or drone, "127.0.0.1", ports[1], 60)
        if where:
            return
        load = [str(h.PYTHON), str(LOADGEN), "--model", str(model), "--ingress", "127.0.0.1:7001"]
        load += ["--seconds", str(self.load_s), "--seed", str(seed), "--signal", "uniform"]
        self.run(f"load-{drone}", drone, load)

    def start_subbroker(
        self, s: str, drone: str, tag: str = "", endpoint: str = "", transport: str = "tcp"
    ) -> h.Proc:
        """Station ``s``'s SubBroker of ``drone`` (its PubBroker at ``endpoint``, by default
        the drone's namespace's address seen from ``s``, port 7000)."""
        path = self.tmp / f"sb-{s}-{drone}.toml"
        path.write_text(f"""model = "{self.models[drone]}"
station = "{s}"
state_dir = "{self.tmp / f"state-{s}-{drone}"}"
[link]
transport = "{transport}"
endpoint = "{endpoint or f"{self.addr[(drone, s)]}:7000"}"
key = "env:MODD_LINK_KEY"
[zenoh]
mode = "client"
listen = []
connect = ["tcp/127.0.0.1:{self.port[s]}"]
credentials_dir = "{self.creds[s]}"
[delivery]
tcp = false
status_period_s = 0.5
""")
        proc = self.run(f"sb-{s}-{drone}{tag}", s, [*h.SUBBROKER, "--config", str(path)])
        proc.dumps_stacks = True
        self.sb[(s, drone)] = proc
        return proc

    def start_viewer(self, s: str) -> Path:
        out = self.tmp / f"viewer-{s}.hex"
        cmd = [str(h.PYTHON), str(Path(__file__).with_name("ns_listener.py"))]
        cmd += ["--connect", f"tcp/127.0.0.1:{self.port[s]}", "--credentials", str(self.creds[s])]
        cmd += ["--out", str(out)]
        assert self.run(f"viewer-{s}", s, cmd).wait_log("listening", 20)
        return out

    def backfill(self, s: str, drone: str, subscriber: str) -> dict[str, Any]:
        cmd = [*self.fabric.prefix(s), str(Path(h.PYTHON).with_name("modd")), "backfill"]
        cmd += ["--drone", drone, "--subscriber", subscriber, "--gaps", "--json"]
        cmd += ["--connect", f"tcp/127.0.0.1:{self.port[s]}", "--timeout", "60"]
        cmd += ["--credentials", str(self.creds[s] / "backend.cred")]
        done = subprocess.run(cmd, capture_output=True, timeout=90, text=True)
        assert done.returncode == 0, (done.stdout[-2000:], done.stderr[-2000:])
        last = [ln for ln in done.stdout.splitlines() if ln.startswith("{")]
        return dict(json.loads(last[-1])) if last else {}

    def stop(self) -> None:
        """SIGTERM to every process first, then each waited for (not one after another)."""
        for p in self.procs:
            if p.alive():
                p.p.terminate()
        for p in reversed(self.procs):
            p.stop()


def read_viewer(path: Path) -> list[DeliveredValue]:
    """The raw zenoh samples a viewer got (each as it came, duplicates included)."""
    raw = [bytes.fromhex(ln) for ln in path.read_text().split()] if path.exists() else []
    return [DeliveredValue.from_json(r) for r in raw if r.startswith(b"{")]


def settled(path: Path, quiet_s: float = 1.5, limit_s: float = 30.0) -> None:
    """Wait until a viewer's two files have not grown for ``quiet_s``: a drone's last
    windows may still come, and the wire's file and the API's, read a moment apart,
    would then differ by them."""
    files = [path, Path(f"{path}.api")]
    sizes, since, end = None, time.monotonic(), time.monotonic() + limit_s
    while time.monotonic() < end:
        now = [f.stat().st_size if f.exists() else -1 for f in files]
        if now != sizes:
            sizes, since = now, time.monotonic()
        elif time.monotonic() - since >= quiet_s:
            return
        time.sleep(0.25)


def read_api(path: Path) -> list[DeliveredValue]:
    """What the subscriber API gave the same viewer."""
    api = Path(f"{path}.api")
    lines = api.read_text().splitlines() if api.exists() else []
    return [DeliveredValue.from_json(ln) for ln in lines]


@pytest.fixture
def campaign(tmp_path: Path) -> Iterator[Campaign]:
    fabric = Fabric()
    try:
        c = Campaign(tmp_path, fabric)
        try:
            yield c
        finally:
            c.stop()
    finally:
        fabric.close()


def wait_serving(c: Campaign, s: str, drone: str, timeout_s: float = 25.0) -> None:
    sb = c.sb[(s, drone)]
    assert sb.wait_log(f"station {s} serves {drone}", timeout_s), sb.log()[-3000:]


def serving_now(c: Campaign, drone: str) -> str:
    """The station whose SubBroker of ``drone`` serves it now, by its log: the latest
    "station s serves" line with no link warning after it (log lines start with their
    time, so two stations' logs compare)."""
    best, who = "", ""
    for (s, d), sb in c.sb.items():
        if d != drone or not sb.alive():
            continue
        lines = sb.log().splitlines()
        served = [ln[:23] for ln in lines if f"station {s} serves {drone}" in ln]
        lost = [ln[:23] for ln in lines if "WARNING modd.subbroker.link: link to" in ln]
        if served and (not lost or served[-1] > lost[-1]) and served[-1] > best:
            best, who = served[-1], s
    return who


@pytest.mark.timeout(240)
def test_three_stations_six_drones_move_kill_partition_each_window_once(
    campaign: Campaign,
) -> None:
    c = campaign
    assert h.PUBBROKER.exists(), f"{h.PUBBROKER} is not built: run make build"
    c.fabric.set_link("usv1", "b", up=False)  # usv1 starts in a's range only
    for s in STATIONS:
        c.start_router(s)
    viewers = {s: c.start_viewer(s) for s in "ac"}
    for i, drone in enumerate(HEARD_BY):
        c.start_drone(drone, seed=i + 1)
    for drone, heard in HEARD_BY.items():
        for s in heard:
            c.start_subbroker(s, drone)
    for drone, heard in HEARD_BY.items():
        wait_serving(c, heard[0], drone)
    time.sleep(6)
    # usv1 moves from a to b
    moved = time.monotonic()
    c.fabric.set_link("usv1", "a", up=False)
    c.fabric.set_link("usv1", "b", up=True)
    wait_serving(c, "b", "usv1", 30)
    print(f"usv1 moved: station b serves it {time.monotonic() - moved:.1f} s later")
    time.sleep(4)
    # station b dies (router and SubBrokers) and comes back
    for key in [k for k in c.sb if k[0] == "b"]:
        c.sb[key].kill9()
    c.routers["b"].kill9()
    killed_ns = time.time_ns()
    time.sleep(4)
    c.start_router("b", "-again")
    for drone in ("usv1", "usv2"):
        c.start_subbroker("b", drone, "-again")
    wait_serving(c, "b", "usv1", 30)
    wait_serving(c, "b", "usv2", 30)
    time.sleep(3)
    # the a-b link partitioned and healed
    c.fabric.set_link("a", "b", up=False)
    time.sleep(6)  # within zenoh's lease (10 s): docs/fleet.md, "A partition"
    c.fabric.set_link("a", "b", up=True)
    for drone in HEARD_BY:
        assert c.procs and any(p.name == f"load-{drone}" for p in c.procs)
    for p in c.procs:
        if p.name.startswith("load-"):
            p.p.wait(LOAD_S + 60)
    time.sleep(2)
    fill_gaps(c)
    time.sleep(2)
    check_viewers(c, viewers, killed_ns)


def fill_gaps(c: Campaign, drones: Iterable[str] = HEARD_BY) -> None:
    """Each drone's serving station fills every subscriber's gaps."""
    for drone in drones:
        s = serving_now(c, drone)
        assert s, f"no station serves {drone}"
        subs = {v.subscriber for v in read_api(c.tmp / "viewer-c.hex") if v.drone == drone}
        for sub in sorted(subs):
            c.backfill(s, drone, sub)


def check_viewers(
    c: Campaign, viewers: dict[str, Path], killed_ns: int, drones: Iterable[str] = HEARD_BY
) -> None:
    """At each viewer, through the subscriber API: every window of every drone once,
    equal to its archive's aggregate, none missing; on the wire (raw samples) none twice
    either, b's kill -9 included (its window journal: docs/fleet.md, "Exactly once")."""
    archives = {d: h.read_archive(c.tmp / d / "archive", c.models[d]) for d in drones}
    for s, path in viewers.items():
        settled(path)
        given, raw = read_api(path), read_viewer(path)
        for drone in drones:
            mine = [v for v in given if v.drone == drone]
            ids = [identity(v) for v in mine]
            dup = len(ids) - len(set(ids))
            assert dup == 0, f"{dup} windows of {drone} twice at the viewer at {s}"
            assert h.check_against_archive({f"{s}/{drone}": mine}, archives[drone]) > 50
            assert_complete(mine, f"{s}/{drone}")
        assert {identity(v) for v in raw} == {identity(v) for v in given}
        twice = len(raw) - len({identity(v) for v in raw})
        assert twice == 0, (
            f"{twice} windows twice on the wire at {s} (b killed at {killed_ns}): "
            f"{repeated(raw)[:12]}"
        )
        filled = sum(v.backfilled for v in given)
        print(f"viewer at {s}: {len(given)} windows ({filled} filled), none twice on the wire")


def repeated(raw: list[DeliveredValue]) -> list[tuple[Any, ...]]:
    """The windows that came more than once, with their places in the stream (to tell
    a station's second put from a late copy)."""
    at: dict[tuple[Any, ...], list[int]] = {}
    for i, v in enumerate(raw):
        at.setdefault(identity(v), []).append(i)
    return [
        (*k, [(i, raw[i].backfilled) for i in v], len(raw)) for k, v in at.items() if len(v) > 1
    ]


def identity(v: DeliveredValue) -> tuple[Any, ...]:
    return (v.drone, v.subscriber, v.epoch_ns, v.window)


def assert_complete(values: list[DeliveredValue], where: str) -> None:
    """Per subscriber and epoch, every window from the first received to the last."""
    by: dict[tuple[str, int], set[int]] = {}
    for v in values:
        assert v.epoch_ns is not None and v.window is not None, (where, v)
        by.setdefault((v.subscriber, v.epoch_ns), set()).add(v.window)
    for (sub, epoch), windows in by.items():
        missing = sorted(set(range(min(windows), max(windows) + 1)) - windows)
        assert not missing, f"{where} {sub} epoch {epoch}: windows {missing[:10]} missing"
