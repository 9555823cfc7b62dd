"""Two stations hearing one drone over a shared radio channel, in network namespaces
(issue 44, docs/fleet.md, "Several stations on one radio channel"): stations a, b, c,
each in its own namespace with its router (full mesh); drone usv1 in its own, its C++
PubBroker on udp behind ``modd-radio``'s shared channel (a modem for a, one for b,
**20 % loss each**, drawn apart), linked to a and b; drone usv2 on tcp, heard by c.
Viewers at a and at c (tests/fleet/ns_listener.py).

The scenario: a serves usv1 while b stands by and forwards what its modem hears
(diversity reception); usv1 moves out of a's range (the link usv1–a cut: a's modem
neither hears it nor reaches it), so a gives it up and b serves; b is killed with -9
(router and SubBroker) and restarted; usv1 comes back into a's range (a stands by and
forwards, b serves); the a–b link is partitioned while both hear usv1, and healed
(b keeps it). Then each drone's serving station fills its gaps. At each viewer: every
window of each drone exactly once (through the subscriber API and on the wire), equal
to the aggregate recomputed from that drone's archive with the official ``mcap``
reader, every epoch's windows there from its first to its last, and no window that
came live was backfilled (union coverage).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "subbroker"))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import subbroker_harness as h  # noqa: E402
from fleet.test_fleet_netns import (  # noqa: E402
    STATIONS,
    Campaign,
    check_viewers,
    fill_gaps,
    identity,
    read_api,
    serving_now,
    wait_serving,
)
from radio_harness import RADIO  # noqa: E402
from support.netns import Fabric, needs_netns  # noqa: E402

pytestmark = needs_netns

HEARD_BY = {"usv1": "ab", "usv2": "c"}
MODEM = {"a": 7101, "b": 7102}  # each station's modem on usv1's shared channel
LOAD_S = 70


@pytest.mark.timeout(240)
def test_two_stations_on_one_radio_move_kill_partition_each_window_once(
    tmp_path: Path,
) -> None:
    assert h.PUBBROKER.exists(), f"{h.PUBBROKER} is not built: run make build"
    fabric = Fabric()
    c = Campaign(tmp_path, fabric, HEARD_BY, LOAD_S)
    try:
        run(c)
    finally:
        c.stop()
        fabric.close()


def run(c: Campaign) -> None:
    for s in STATIONS:
        c.start_router(s)
    viewers = {s: c.start_viewer(s) for s in "ac"}
    c.start_drone("usv1", seed=1, transport="udp")
    modems = [a for m in MODEM.values() for a in ("--udp", f"0.0.0.0:{m}")]
    radio = [*RADIO, *modems, "--to", "127.0.0.1:7000", "--radio", "loss=0.2,seed=44"]
    c.run("radio-usv1", "usv1", [*radio, "--report", "5"])
    c.start_drone("usv2", seed=2)
    c.start_subbroker("c", "usv2")
    for s in "ab":  # a first: started together, either may win the drone (both hear it)
        endpoint = f"{c.addr[('usv1', s)]}:{MODEM[s]}"
        c.start_subbroker(s, "usv1", endpoint=endpoint, transport="udp")
        if s == "a":
            wait_serving(c, "a", "usv1")
    wait_serving(c, "c", "usv2")
    time.sleep(8)  # a serves, b forwards what its modem hears
    moved = time.monotonic()
    c.fabric.set_link("usv1", "a", up=False)  # usv1 leaves a's range
    wait_serving(c, "b", "usv1", 40)
    print(f"usv1 moved: station b serves it {time.monotonic() - moved:.1f} s later")
    time.sleep(4)
    c.sb[("b", "usv1")].kill9()
    c.routers["b"].kill9()
    killed_ns = time.time_ns()
    time.sleep(4)
    c.start_router("b", "-again")
    endpoint = f"{c.addr[('usv1', 'b')]}:{MODEM['b']}"
    c.start_subbroker("b", "usv1", "-again", endpoint=endpoint, transport="udp")
    wait_serving(c, "b", "usv1", 30)
    time.sleep(3)
    c.fabric.set_link("usv1", "a", up=True)  # back in a's range: a stands by, forwards
    time.sleep(5)
    c.fabric.set_link("a", "b", up=False)  # both hear usv1, neither sees the other
    time.sleep(8)  # within zenoh's lease (10 s): a still sees b's serving token
    c.fabric.set_link("a", "b", up=True)
    for p in c.procs:
        if p.name.startswith("load-"):
            p.p.wait(LOAD_S + 60)
    time.sleep(2)
    assert serving_now(c, "usv1") == "b", "a back in range stands by: b keeps usv1"
    fill_gaps(c, HEARD_BY)
    time.sleep(2)
    check_viewers(c, viewers, killed_ns, HEARD_BY)
    for s, path in viewers.items():
        given = [v for v in read_api(path) if v.drone == "usv1"]
        live = {identity(v) for v in given if not v.backfilled}
        filled = {identity(v) for v in given if v.backfilled}
        assert not live & filled, f"{len(live & filled)} live windows backfilled at {s}"
        print(f"usv1 at the viewer at {s}: {len(live)} live, {len(filled)} backfilled")
