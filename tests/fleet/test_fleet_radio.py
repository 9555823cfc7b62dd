"""Two stations hearing one drone over one radio channel (issue 44, docs/fleet.md,
"Several stations on one radio channel"), real processes on loopback: the C++
PubBroker on a udp link behind ``modd-radio`` in its shared-channel mode (one modem
per station, 20 % of the datagrams lost at each, drawn apart in both directions),
two station routers in a mesh, a SubBroker per station on the same drone (``station``
set: one serves, the other stands by), a viewer at each station.

Station a serves; it is killed with -9 (SubBroker and router) and b takes the drone
over through its own modem; a comes back and stands by; b fills the gaps
(``backfill --gaps``) of every subscriber. At each viewer, on the raw zenoh samples:
every window once (by identity), equal to the aggregate recomputed from the drone's
archive with the official ``mcap`` reader, every window of every epoch of the 0.25-s
subscriptions there from its first to its last; and **union coverage**: no window
either station delivered (live, or heard by the other through the mesh) was
backfilled, i.e. what came back with ``backfilled`` set is disjoint from what came live;
and what b's modem heard while no station served (a dead, b not yet up) is delivered at
the takeover, read under a's session, not backfilled.

Diversity reception: station a's modem hears nothing of the drone for 15 s (its
receiver blocked; the drone still hears a), b's hears every datagram; b stands by and
forwards what its modem hears, so a keeps the drone and every window comes live: none
is left for a backfill.
"""

from __future__ import annotations

import json
import re
import sys
import time
from pathlib import Path
from typing import Any

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from fleet.test_fleet import (  # noqa: E402
    TAKEOVER_S,
    Listener,
    assert_every_window,
    backfill,
    first_after,
    identities,
    mesh,
    procs,  # noqa: F401  (the fixture)
    start_subbroker,
    subbroker_toml,
)
from radio_harness import RADIO, radio_counts, start_pubbroker_dgram  # noqa: E402
from subbroker_harness import (  # noqa: E402
    PUBBROKER,
    Proc,
    check_against_archive,
    free_port,
    model_copy,
    read_archive,
    start_load,
)

LOSS = "loss=0.2,seed=44"
LOAD_S = 50
SUBSCRIBERS = ("sub_3", "sub_4", "sub_5", "sub_6", "sub_7")  # scenario 1's 0.25-s ones


def start_shared_radio(
    tmp: Path, target: int, modems: list[int], radios: tuple[str, ...] = (LOSS,)
) -> Proc:
    """The shared channel: ``radios`` once for every modem, or one per modem."""
    listens = [a for m in modems for a in ("--udp", f"127.0.0.1:{m}")]
    settings = [a for r in radios for a in ("--radio", r)]
    cmd = [*RADIO, *listens, "--to", f"127.0.0.1:{target}", *settings, "--report", "1"]
    proc = Proc("radio", cmd, tmp / "radio.log")
    time.sleep(0.3)
    return proc


class SharedChannel:
    """Two stations a and b in a mesh, the C++ PubBroker on udp behind the shared
    channel (``radios``: once for both modems, or one each), a viewer at each station and
    each station's SubBroker configuration (``sb``), not started."""

    def __init__(self, tmp: Path, started: list[Any], radios: tuple[str, ...]) -> None:
        assert PUBBROKER.exists(), f"{PUBBROKER} is not built: run make build"
        self.tmp, self.started = tmp, started
        self.stations = mesh(tmp, "ab")
        for s in self.stations.values():
            started.append(s.start())
        link, self.ingress = free_port("udp"), free_port()
        self.model = model_copy(tmp, "scenario1.modd")
        udp = {"transport": "udp", "port": link}
        started.append(start_pubbroker_dgram(tmp, self.model, udp, self.ingress))
        modems = {"a": free_port("udp"), "b": free_port("udp")}
        self.radio = start_shared_radio(tmp, link, list(modems.values()), radios)
        started.append(self.radio)
        self.viewers = {s: Listener(st, "modd/usv/sub/*") for s, st in self.stations.items()}
        started.extend(self.viewers.values())
        self.sb = {
            s: subbroker_toml(tmp, self.model, modems[s], st, "udp", str(tmp / s))
            for s, st in self.stations.items()
        }

    def start_subbrokers(self) -> tuple[Proc, Proc]:
        """a's SubBroker, serving, then b's (it stands by)."""
        sb_a = start_subbroker(self.tmp, self.sb["a"], "sb-a")
        self.started.append(sb_a)
        assert sb_a.wait_log("station a serves usv", 30), sb_a.log()
        sb_b = start_subbroker(self.tmp, self.sb["b"], "sb-b")
        self.started.append(sb_b)
        return sb_a, sb_b


@pytest.mark.timeout(240)
def test_two_stations_on_one_radio_channel_each_window_once_union_coverage(
    tmp_path: Path,
    procs: list[Any],  # noqa: F811
) -> None:
    ch = SharedChannel(tmp_path, procs, (LOSS,))
    a, b, at, sb = ch.stations["a"], ch.stations["b"], ch.viewers, ch.sb
    sb_a, sb_b = ch.start_subbrokers()
    model, ingress, radio = ch.model, ch.ingress, ch.radio
    procs.append(load := start_load(tmp_path, model, ingress, LOAD_S))
    time.sleep(15)  # b stands by while a serves over the lossy channel
    assert "serves usv" not in sb_b.log(), sb_b.log()
    assert len(at["b"].values()) > 20, "a's values reach the viewer at b through the mesh"
    sb_a.kill9()
    assert a.proc is not None
    a.proc.kill9()
    killed_ns = time.time_ns()
    assert sb_b.wait_log("station b serves usv", TAKEOVER_S + 10), sb_b.log()
    assert "adopting config" in sb_b.log(), "b takes the config the PubBroker runs"
    # what b's modem heard while no station served, read under a's session: delivered
    took = re.search(r"took over with (\d+) datagrams .* (\d+) values delivered", sb_b.log())
    assert took is not None and int(took.group(2)) > 0, sb_b.log()
    back = first_after(at["b"], killed_ns, TAKEOVER_S + 10)
    assert back is not None, sb_b.log()
    procs.append(a.start("-again"))
    procs.append(sb_a2 := start_subbroker(tmp_path, sb["a"], "sb-a-again"))
    load.p.wait(LOAD_S + 60)
    time.sleep(3)
    assert sb_a2.log().count("serves usv") == 0, "a back stands by: b serves"
    for sub in SUBSCRIBERS:
        job = backfill(b, {"op": "start", "subscriber": sub, "gaps": True})
        assert sb_b.wait_log(f"backfill {job['id']} for {sub}: DONE", 60), sb_b.log()[-3000:]
    time.sleep(2)
    check(tmp_path, model, at)
    print(f"takeover over the radio: first value at b {back:.2f} s after a was killed")
    print(f"b delivered {took.group(2)} values from {took.group(1)} datagrams its modem heard")
    print(radio_counts(radio))


def check(tmp: Path, model: Path, at: dict[str, Listener]) -> None:
    archive = read_archive(tmp / "archive", model)
    for name, listener in at.items():
        values = listener.values()
        ids = identities(values)
        dup = len(ids) - len(set(ids))
        assert dup == 0, f"{dup} windows twice at station {name}'s viewer (raw samples)"
        assert check_against_archive({name: values}, archive) > 100
        live = {i for v, i in zip(values, ids, strict=True) if not v.backfilled}
        filled = {i for v, i in zip(values, ids, strict=True) if v.backfilled}
        assert not live & filled, f"{len(live & filled)} windows delivered live were backfilled"
        for sub in SUBSCRIBERS:  # one grid across the handover (b adopted a's config)
            assert_every_window([v for v in values if v.subscriber == sub], epochs=1)
        print(f"viewer at {name}: {len(ids)} windows, {len(filled)} backfilled, none twice")


@pytest.mark.timeout(200)
def test_a_window_the_standby_stations_modem_got_is_delivered_live(
    tmp_path: Path,
    procs: list[Any],  # noqa: F811
) -> None:
    """Union coverage by diversity reception: a's modem loses 20 % and then hears
    nothing of the drone for 15 s (the drone still hears a), b's loses nothing. b never
    serves; a delivers every window live from what the two modems heard (b's forwarded
    through the mesh), each once, equal to the archive; a backfill of the gaps finds
    none. Without the forwarding, a's link goes silent in the outage and b takes the
    drone over: a handover, its gap backfilled."""
    ch = SharedChannel(tmp_path, procs, ("loss=0.2,seed=45,deaf=18+15", "loss=0"))
    a, at = ch.stations["a"], ch.viewers
    procs.append(status := Listener(a, "modd/usv/status"))
    sb_a, sb_b = ch.start_subbrokers()
    model, ingress, radio = ch.model, ch.ingress, ch.radio
    procs.append(load := start_load(tmp_path, model, ingress, 40))
    load.p.wait(100)
    time.sleep(3)
    assert "serves usv" not in sb_b.log(), "a kept the drone: b never served"
    for sub in SUBSCRIBERS:  # no gap: nothing to ask the drone for
        job = backfill(a, {"op": "start", "subscriber": sub, "gaps": True}, expect="DONE")
        assert job["windows"] == 0, job
    archive = read_archive(tmp_path / "archive", model)
    for name, listener in at.items():
        values = listener.values()
        ids = identities(values)
        assert len(ids) == len(set(ids)), f"a window twice at station {name}'s viewer"
        assert check_against_archive({name: values}, archive) > 100
        filled = [v for v in values if v.backfilled]
        assert not filled, f"{len(filled)} windows backfilled that station b's modem got"
        for sub in SUBSCRIBERS:
            assert_every_window([v for v in values if v.subscriber == sub], epochs=1)
    radio_of_a = [json.loads(r).get("radio") or {} for r in status.raw]
    used = max(r.get("heard_elsewhere_used", 0) for r in radio_of_a)
    # a datagram carries up to the accepted delay (1 s) of slots: 15 s, 15 datagrams at least
    assert used >= 15, f"the outage's datagrams came from b's modem ({used})"
    replayed = max(r.get("replayed", 0) for r in radio_of_a)
    assert replayed == 0, f"{replayed} copies (both modems heard them) counted as replays"
    print(f"station a took {used} datagrams from b's modem; {radio_counts(radio)}")
