"""Issue 44's benchmark: N simulated drones (scenario 1's load each) across three base
stations joined by zenoh's router mesh, in network namespaces (run as root).

- Stations a, b, c: one namespace each (full mesh of veth links), a station router each
  (``python -m modd.station``), and per drone it serves a SubBroker (``station`` set).
- Drones: N-1 of them inside their station's namespace (the C++ PubBroker on loopback,
  archive on), fed by one load process per station (benchkit/fleet_procs.py); one more,
  ``h00``, in a namespace of its own linked to a and b, heard by both (a serves it).
- A subscriber in a fourth namespace, linked to station a only, gets every value of
  every drone (``modd/*/sub/*``, raw zenoh samples: benchkit/fleet_viewer.py).

Reports, over ``--seconds``: CPU (% of one core) and resident memory (median of the
samples) per station (its router, its SubBrokers, their sum); the end-to-end latency
from a window's end (``end_ns``: drone clock = this machine's) to its receipt by the
subscriber, p50 / p99 / max; windows delivered twice (by identity); and a handover:
h00's SubBroker at a is killed with -9, b takes it over, then fills the gap
(``modd backfill --gaps``): the time from the kill to b serving, and to the gap's last
window at the subscriber.

    .venv/bin/python tests/bench/bench_fleet_stations.py                 # 50 drones, 60 s
    .venv/bin/python tests/bench/bench_fleet_stations.py --drones 7 --seconds 10
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from collections import defaultdict
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
for p in (HERE, HERE.parent / "subbroker", HERE.parent):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import subbroker_harness as h  # noqa: E402
from benchkit.footprint import Footprint, Sampler  # noqa: E402
from fleet.test_fleet_netns import STATIONS, Campaign  # noqa: E402
from support.netns import Fabric, netns_works  # noqa: E402

MOVER = "h00"
FLEET_PROCS = HERE / "benchkit" / "fleet_procs.py"
VIEWER = HERE / "benchkit" / "fleet_viewer.py"
SUBSCRIBERS = [f"sub_{i}" for i in range(1, 8)]


class Bench(Campaign):
    """The campaign test's namespaces and processes (tests/fleet/test_fleet_netns.py), with
    the mover in a namespace of its own, a viewer's namespace linked to a, and the other
    drones in their stations' namespaces."""

    def __init__(self, tmp: Path, drones: int, load_s: float) -> None:
        super().__init__(tmp, Fabric(), {MOVER: "ab"}, load_s)
        self._link("v", "a")
        self.home = {f"d{i:02d}": STATIONS[(i - 1) % 3] for i in range(1, drones)}

    def stop(self) -> None:
        super().stop()
        self.fabric.close()


def start_drones(b: Bench) -> None:
    """Every drone's PubBroker and load, then its serving SubBroker."""
    targets: dict[str, list[list[Any]]] = defaultdict(list)
    for n, (drone, s) in enumerate(b.home.items()):
        b.start_drone(drone, 0, where=s, ports=(7100 + 2 * n, 7101 + 2 * n))
        targets[s].append([drone, 7101 + 2 * n, str(b.models[drone])])
    b.start_drone(MOVER, 1)
    for s, t in targets.items():
        cmd = [str(h.PYTHON), str(FLEET_PROCS), "load", "--targets", json.dumps(t)]
        b.run(f"load-{s}", s, [*cmd, "--seconds", str(b.load_s)])
    for n, (drone, s) in enumerate(b.home.items()):
        b.start_subbroker(s, drone, endpoint=f"127.0.0.1:{7100 + 2 * n}")
    b.start_subbroker("a", MOVER)


def start_standby(b: Bench) -> None:
    """b's SubBroker of the mover, once a serves it (started with the others, on a loaded
    machine b could come up first and serve: no hand-back then)."""
    b.start_subbroker("b", MOVER)


def wait_all_serving(b: Bench, timeout_s: float) -> float:
    t0 = time.monotonic()
    deadline = t0 + timeout_s
    for drone, s in [*b.home.items(), (MOVER, "a")]:
        left = max(1.0, deadline - time.monotonic())
        assert b.sb[(s, drone)].wait_log(f"station {s} serves {drone}", left), b.sb[
            (s, drone)
        ].log()[-2000:]
    return time.monotonic() - t0


def station_pids(b: Bench) -> dict[str, list[int]]:
    out: dict[str, list[int]] = {s: [b.routers[s].pid] for s in STATIONS}
    for (s, _), proc in b.sb.items():
        out[s].append(proc.pid)
    return out


def measure(b: Bench, seconds: float) -> dict[str, list[tuple[str, Footprint]]]:
    samplers = {
        s: [
            (("router" if i == 0 else "subbroker"), Sampler(pid).start()) for i, pid in enumerate(p)
        ]
        for s, p in station_pids(b).items()
    }
    time.sleep(seconds)
    return {s: [(kind, sm.stop()) for kind, sm in lst] for s, lst in samplers.items()}


def handover(b: Bench) -> dict[str, float]:
    """Kill a's SubBroker of the mover; b serves it, then fills the gap."""
    killed = time.time_ns()
    b.sb[("a", MOVER)].kill9()
    assert b.sb[("b", MOVER)].wait_log(f"station b serves {MOVER}", 60), "no takeover"
    served_s = (time.time_ns() - killed) / 1e9
    time.sleep(3)
    for sub in SUBSCRIBERS:
        b.backfill("b", MOVER, sub)
    return {"killed_ns": killed, "served_s": served_s}


def read_rows(path: Path) -> list[list[Any]]:
    return [json.loads(ln) for ln in path.read_text().splitlines() if ln.endswith("]")]


def latency_ms(rows: list[list[Any]], lo_ns: int, hi_ns: int) -> tuple[float, float, float, int]:
    lat = sorted((r[0] - r[5]) / 1e6 for r in rows if lo_ns <= r[0] <= hi_ns and not r[6])
    if not lat:
        return (0.0, 0.0, 0.0, 0)
    p99 = lat[min(len(lat) - 1, int(0.99 * len(lat)))]
    return (statistics.median(lat), p99, lat[-1], len(lat))


def report(
    args: argparse.Namespace,
    foot: dict[str, list[tuple[str, Footprint]]],
    rows: list[list[Any]],
    window: tuple[int, int],
    hand: dict[str, float],
    started_s: float,
) -> None:
    print(
        f"{args.drones} drones (scenario 1 each), 3 stations, {args.seconds:.0f} s measured; "
        f"every drone served {started_s:.1f} s after its SubBroker started"
    )
    head = ("station", "SubBrokers", "router CPU % / RSS MB", "SubBrokers' sums", "total")
    print("| " + " | ".join(head) + " |")
    print("| --- | --- | --- | --- | --- |")
    for s, lst in foot.items():
        r = [f for k, f in lst if k == "router"]
        sbs = [f for k, f in lst if k == "subbroker"]
        rc, rm = sum(f.cpu_percent for f in r), sum(f.rss_median_kb for f in r) / 1024
        sc, sm = sum(f.cpu_percent for f in sbs), sum(f.rss_median_kb for f in sbs) / 1024
        cells = (f"{rc:.1f} / {rm:.0f}", f"{sc:.1f} / {sm:.0f}", f"{rc + sc:.1f} / {rm + sm:.0f}")
        print(f"| {s} | {len(sbs)} | " + " | ".join(cells) + " |")
    p50, p99, mx, n = latency_ms(rows, *window)
    print(
        f"latency window end -> subscriber (4th namespace), {n} live values: "
        f"p50 {p50:.1f} ms, p99 {p99:.1f} ms, max {mx:.1f} ms"
    )
    ids = [tuple(r[1:5]) for r in rows]
    print(f"values at the subscriber: {len(ids)}, windows twice: {len(ids) - len(set(ids))}")
    gap = [r for r in rows if r[1] == MOVER and r[6]]
    closed = (max(r[0] for r in gap) - hand["killed_ns"]) / 1e9 if gap else float("nan")
    print(
        f"handover: b served {MOVER} {hand['served_s']:.1f} s after a's SubBroker was killed; "
        f"{len(gap)} gap windows filled, the last at the subscriber {closed:.1f} s after the kill"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--drones", type=int, default=50)
    ap.add_argument("--seconds", type=float, default=60.0)
    args = ap.parse_args()
    if args.drones < 4:
        ap.error("--drones: at least 4 (three stations and the one that moves)")
    if not netns_works():
        print("bench_fleet_stations: needs root and ip netns (skipped)")
        return 0
    import tempfile

    with tempfile.TemporaryDirectory(prefix="modd-fleet-stations-") as tmp:
        b = Bench(Path(tmp), args.drones, load_s=args.seconds + 150)
        try:
            for s in STATIONS:
                b.start_router(s)
            viewer_out = Path(tmp) / "viewer.jsonl"
            where = f"tcp/{b.addr[('a', 'v')]}:{b.port['a']}"
            cmd = [str(h.PYTHON), str(VIEWER), "--connect", where]
            cmd += ["--credentials", str(b.creds["a"]), "--out", str(viewer_out)]
            assert b.run("viewer", "v", cmd).wait_log("listening", 60)
            start_drones(b)
            started_s = wait_all_serving(b, 300)
            start_standby(b)
            time.sleep(10)  # settled
            lo = time.time_ns()
            foot = measure(b, args.seconds)
            hi = time.time_ns()
            hand = handover(b)
            time.sleep(3)
            report(args, foot, read_rows(viewer_out), (lo, hi), hand, started_s)
        finally:
            b.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
