"""Fleet at the base station: N simulated drones on one machine, each a real PubBroker
(C++, archive on) fed at scenario 2's load (19 topics at 25 Hz) and its SubBroker, all
SubBrokers on one zenoh router (a Python session in router mode), one backend
(``modd-backend``) on that router, and one WebSocket client per drone playing the browser's
Monitor: it subscribes to every subscriber of its drone (scenario 2's 19 plus 50 more) on
``/api/drones/<drone>/stream``.

Reports CPU (% of one core, /proc utime + stime over the measured interval) and memory
(VmRSS, median) per drone (PubBroker, SubBroker) and for the shared processes, the values
per second reaching the WebSocket clients, what the backend dropped, and the end-to-end
latency from a window's end (the ``end_ns`` the value carries: config epoch + slot date,
the drone's clock = this machine's) to its receipt by the WebSocket client.

    .venv/bin/python tests/bench/bench_fleet.py                      # 20 drones, 60 s
    .venv/bin/python tests/bench/bench_fleet.py --drones 2 --seconds 5

Target (issue 18): p99 window end -> browser <= 250 ms with 20 drones.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import statistics
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
for p in (HERE, HERE.parent / "subbroker"):
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

import httpx2 as httpx  # noqa: E402
from benchkit.footprint import Footprint, Sampler  # noqa: E402
from modd.zenoh_auth import CredentialStore  # noqa: E402
from modd_model import load_model  # noqa: E402
from subbroker_harness import (  # noqa: E402
    PYTHON,
    SCENARIOS,
    SUBBROKER,
    Proc,
    free_port,
    start_pubbroker,
    wait_port,
)

PASSWORD = "bench-fleet-admin"
EXTRA_PERIODS = ["0.5", "1.0", "2.0"]
EXTRA_AGGREGATIONS = ["MIN", "MAX", "AVERAGE", "LAST", "COUNT"]


def drone_model(index: int, extra: int) -> dict[str, Any]:
    """Scenario 2 as drone ``d<index>`` (topics renamed), plus ``extra`` subscribers."""
    text = json.dumps(load_model(SCENARIOS / "scenario2.modd"))
    model: dict[str, Any] = json.loads(text.replace('"usv.', f'"d{index}.'))
    model["drone"]["name"] = f"d{index}"
    rng = random.Random(index)
    topics = [t for p in model["publishers"] for t in p["topics"]]
    for sub in model["subscribers"]:
        sub.pop("endpoint", None)
    model["subscribers"] += [
        {
            "name": f"x{k}",
            "topic": rng.choice(topics),
            "periodS": rng.choice(EXTRA_PERIODS),
            "aggregation": rng.choice(EXTRA_AGGREGATIONS),
        }
        for k in range(extra)
    ]
    return model


@dataclass
class Drone:
    name: str
    model: dict[str, Any]
    link: int
    ingress: int
    pubbroker: Proc | None = None
    subbroker: Proc | None = None

    @property
    def subscribers(self) -> list[str]:
        return [s["name"] for s in self.model["subscribers"]]

    @property
    def values_per_s(self) -> float:
        return sum(1 / float(s["periodS"]) for s in self.model["subscribers"])


def subbroker_toml(
    tmp: Path, drone: Drone, model_path: Path, router: int, credentials: Path
) -> Path:
    path = tmp / f"{drone.name}.toml"
    path.write_text(f"""
model = {json.dumps(str(model_path))}
[link]
endpoint = "127.0.0.1:{drone.link}"
key = "env:MODD_LINK_KEY"
[zenoh]
mode = "client"
connect = ["tcp/127.0.0.1:{router}"]
listen = []
credentials_dir = {json.dumps(str(credentials))}
[delivery]
tcp = false
status_period_s = 1.0
""")
    return path


@dataclass
class Browser:
    """The WebSocket clients (one per drone) and what they received."""

    seen: dict[str, set[str]] = field(default_factory=dict)
    latencies_ns: list[int] = field(default_factory=list)
    values: int = 0
    dropped: int = 0
    behind: set[str] = field(default_factory=set)
    max_lag_s: float = 0.0
    marked: bool = False

    def on_message(self, drone: str, msg: dict[str, Any]) -> None:
        kind = msg.get("type")
        if kind == "batch":  # ?batch=1, as the workbench's Monitor asks
            for m in msg["messages"]:
                self.on_message(drone, m)
        elif kind == "value":
            self.seen.setdefault(drone, set()).add(msg["subscriber"])
            if self.marked:
                self.values += 1
                self.latencies_ns.append(time.time_ns() - int(msg["data"]["end_ns"]))
        elif kind == "dropped" and self.marked:
            self.dropped += int(msg["count"])
        elif kind == "status" and self.marked:
            data = msg["data"]
            if data.get("behind"):
                self.behind.add(drone)
            self.max_lag_s = max(self.max_lag_s, float(data.get("lag_s") or 0.0))


async def browse(url: str, token: str, drone: Drone, browser: Browser, stop: asyncio.Event) -> None:
    import websockets

    async with websockets.connect(url, max_queue=None) as ws:
        await ws.send(json.dumps({"op": "auth", "token": token}))  # never in the URL
        for name in drone.subscribers:
            await ws.send(json.dumps({"op": "subscribe", "subscriber": name}))
        while not stop.is_set():
            try:
                raw = await asyncio.wait_for(ws.recv(), 0.5)
            except TimeoutError:
                continue
            browser.on_message(drone.name, json.loads(raw))


@dataclass
class Result:
    drones: int
    seconds: float
    asked_per_s: float
    browser: Browser
    pubbrokers: list[Footprint]
    subbrokers: list[Footprint]
    shared: dict[str, Footprint]

    def latency_ms(self, q: float) -> float:
        xs = sorted(self.browser.latencies_ns)
        return xs[min(len(xs) - 1, int(q * len(xs)))] / 1e6 if xs else float("nan")

    def render(self) -> str:
        b = self.browser
        med = statistics.median

        def cpu(fps: list[Footprint]) -> str:
            return (
                f"{med(f.cpu_percent for f in fps):.1f} % "
                f"(max {max(f.cpu_percent for f in fps):.1f} %)"
            )

        def rss(fps: list[Footprint]) -> str:
            return f"{med(f.rss_median_kb for f in fps) / 1024:.1f} MB"

        lines = [
            f"Fleet: {self.drones} drones x (scenario 2 + 50 subscribers), one zenoh router, "
            f"one backend, one WebSocket client per drone; {self.seconds:.0f} s measured",
            "",
            "| per drone | CPU % of a core, median (max) | RSS, median |",
            "| --- | ---: | ---: |",
            f"| PubBroker (C++, archive on, 475 samples/s) | {cpu(self.pubbrokers)} "
            f"| {rss(self.pubbrokers)} |",
            f"| SubBroker (Python) | {cpu(self.subbrokers)} | {rss(self.subbrokers)} |",
            "",
            "| shared | CPU % of a core | RSS |",
            "| --- | ---: | ---: |",
        ]
        for name, fp in self.shared.items():
            lines.append(f"| {name} | {fp.cpu_percent:.1f} % | {fp.rss_median_kb / 1024:.1f} MB |")
        lines += [
            "",
            "| values asked /s | received /s (WebSocket) | dropped by the backend | "
            "p50 ms | p99 ms | max ms | SubBrokers behind | max lag_s |",
            "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
            f"| {self.asked_per_s:,.0f} | {b.values / self.seconds:,.0f} | {b.dropped} | "
            f"{self.latency_ms(0.5):.1f} | {self.latency_ms(0.99):.1f} | "
            f"{self.latency_ms(1.0):.1f} | {len(b.behind)} | {b.max_lag_s:.3f} |",
        ]
        return "\n".join(lines)


def start_backend(tmp: Path, router: int, credentials: Path) -> tuple[Proc, int]:
    """Started, not waited for (it imports for seconds): wait_port(port) before use."""
    port = free_port()
    exe = str(Path(PYTHON).with_name("modd-backend"))
    data = tmp / "backend"
    data.mkdir()
    proc = Proc(
        "backend",
        [
            exe,
            "--port",
            str(port),
            "--data",
            str(data),
            "--zenoh-connect",
            f"tcp/127.0.0.1:{router}",
            "--zenoh-credentials",
            str(credentials / "backend.cred"),
            "--deploy-key",
            str(credentials / "deploy.key"),
            "--scene-port",
            "-1",
        ],
        tmp / "backend.log",
        env={"MODD_ADMIN_PASSWORD": PASSWORD},
    )
    return proc, port


def start_drone(tmp: Path, drone: Drone, model_path: Path) -> Proc:
    """The drone's PubBroker on free ports (taken again if another process took them
    between the choice and the bind: the machine is shared)."""
    for attempt in range(3):
        drone.link, drone.ingress = free_port(), free_port()
        try:
            proc = start_pubbroker(tmp, model_path, drone.link, drone.ingress, tag=f"pb{attempt}")
        except TimeoutError:  # it died before listening
            continue
        time.sleep(0.1)
        if proc.alive():
            return proc
        proc.stop()
    raise RuntimeError(f"{drone.name}: the PubBroker did not start (see {tmp})")


def wait_all_seen(
    browser: Browser, drones: list[Drone], procs: list[Proc], timeout_s: float
) -> None:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if all(browser.seen.get(d.name, set()) >= set(d.subscribers) for d in drones):
            return
        for p in procs:
            if not p.alive():
                raise RuntimeError(f"{p.name} exited:\n{p.log()[-2000:]}")
        time.sleep(0.2)
    missing = {
        d.name: sorted(set(d.subscribers) - browser.seen.get(d.name, set()))[:5]
        for d in drones
        if set(d.subscribers) - browser.seen.get(d.name, set())
    }
    raise RuntimeError(f"no value within {timeout_s} s for {missing}")


async def _run(tmp: Path, n: int, seconds: float, extra: int, batched: bool = True) -> Result:
    procs: list[Proc] = []
    router = free_port()
    kit = str(HERE / "benchkit" / "fleet_procs.py")
    # as deployed: the router authenticates every client and applies access control
    credentials = tmp / "credentials"
    CredentialStore(credentials).ensure()
    procs.append(
        Proc(
            "router",
            [
                str(PYTHON),
                kit,
                "router",
                "--listen",
                f"tcp/127.0.0.1:{router}",
                "--credentials",
                str(credentials),
            ],
            tmp / "router.log",
        )
    )
    try:
        if not procs[0].wait_log("ready", 30):
            raise RuntimeError(f"router: {procs[0].log()}")
        backend, port = start_backend(tmp, router, credentials)
        procs.append(backend)
        drones = [Drone(f"d{i}", drone_model(i, extra), 0, 0) for i in range(n)]
        targets = []
        for d in drones:
            dtmp = tmp / d.name
            dtmp.mkdir()
            path = dtmp / "model.json"
            path.write_text(json.dumps(d.model))
            d.pubbroker = start_drone(dtmp, d, path)
            d.subbroker = Proc(
                f"sb-{d.name}",
                [*SUBBROKER, "--config", str(subbroker_toml(dtmp, d, path, router, credentials))],
                dtmp / "sb.log",
            )
            procs += [d.pubbroker, d.subbroker]
            targets.append([d.name, d.ingress, str(path)])
        load = Proc(
            "load",
            [
                str(PYTHON),
                kit,
                "load",
                "--targets",
                json.dumps(targets),
                "--seconds",
                str(seconds + 300),
            ],
            tmp / "load.log",
        )
        procs.append(load)
        await asyncio.to_thread(wait_port, port, 180)
        tokens = {}
        async with httpx.AsyncClient(base_url=f"http://127.0.0.1:{port}", timeout=30) as c:
            r = await c.post("/api/auth/login", json={"username": "admin", "password": PASSWORD})
            r.raise_for_status()
            admin = {"Authorization": f"Bearer {r.json()['token']}"}
            # one scientist per drone, as on a real base station: the backend caps
            # live subscriptions per user (1,024) and a fleet asks for more
            for d in drones:
                user = f"scientist_{d.name}"
                r = await c.post(
                    "/api/users",
                    headers=admin,
                    json={"username": user, "password": PASSWORD, "roles": ["scientist"]},
                )
                r.raise_for_status()
                r = await c.post("/api/auth/login", json={"username": user, "password": PASSWORD})
                r.raise_for_status()
                tokens[d.name] = r.json()["token"]
        browser, stop = Browser(), asyncio.Event()
        tasks = [
            asyncio.create_task(
                browse(
                    f"ws://127.0.0.1:{port}/api/drones/{d.name}/stream"
                    + ("?batch=1" if batched else ""),
                    tokens[d.name],
                    d,
                    browser,
                    stop,
                )
            )
            for d in drones
        ]
        await asyncio.to_thread(wait_all_seen, browser, drones, procs, 60 + 3 * n)
        samplers = [
            Sampler(p.pid).start()
            for d in drones
            for p in (d.pubbroker, d.subbroker)
            if p is not None
        ]
        shared = {
            "zenoh router (Python, router mode)": procs[0],
            "backend": backend,
            "publisher load (all drones, Python)": load,
        }
        shared_samplers = {k: Sampler(p.pid).start() for k, p in shared.items()}
        shared_samplers["WebSocket clients (this process, all drones)"] = Sampler(
            os.getpid()
        ).start()
        browser.marked = True
        t0 = time.monotonic()
        await asyncio.sleep(seconds)
        browser.marked = False
        measured = time.monotonic() - t0
        fps = [s.stop() for s in samplers]
        shared_fps = {k: s.stop() for k, s in shared_samplers.items()}
        stop.set()
        for t in tasks:
            t.cancel()
        await asyncio.gather(*tasks, return_exceptions=True)
        return Result(
            n,
            measured,
            sum(d.values_per_s for d in drones),
            browser,
            fps[0::2],
            fps[1::2],
            shared_fps,
        )
    finally:
        for p in reversed(procs):
            p.stop()


def run(drones: int, seconds: float, extra: int = 50, batched: bool = True) -> Result:
    with tempfile.TemporaryDirectory(prefix="modd-fleet-") as tmp:
        return asyncio.run(_run(Path(tmp), drones, seconds, extra, batched))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--drones", type=int, default=20)
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--extra-subscribers", type=int, default=50)
    ap.add_argument(
        "--unbatched",
        action="store_true",
        help="one WebSocket frame per value (the stream's default without ?batch=1)",
    )
    args = ap.parse_args(argv)
    start = time.monotonic()
    result = run(args.drones, args.seconds, args.extra_subscribers, not args.unbatched)
    print(f"WebSocket frames: {'one per value' if args.unbatched else 'batched (?batch=1)'}")
    print(result.render())
    print(f"\n(whole run {time.monotonic() - start:.0f} s, start-up included)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
