"""Health under a WebSocket subscription flood: one socket sends N
``subscribe`` ops (distinct names; refused past the per-socket cap) while
``GET /api/health`` is polled; prints its latency percentiles. A real
``modd-backend`` process on loopback (zenoh on, no peers). Asserts nothing.

    .venv/bin/python tests/bench/bench_health_ws.py [--ops 20000]

It first polls health for 3 s with no load (the machine's own noise), then
during the flood until every reply is read.

Target (issue 22): p99 <= 50 ms during 20,000 ops (was up to ~3 minutes of
health timeouts: one zenoh subscriber and OS thread per op, on the event loop).
"""

from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

import httpx2 as httpx
from modd.ports import free_port
from websockets.sync.client import connect

PASSWORD = "bench-admin-password"


def _poll(
    c: httpx.Client, base: str, stop: Callable[[], bool], seconds: float = 600.0
) -> list[float]:
    """Latencies (ms) of GET /api/health every 5 ms until ``stop()`` or ``seconds``."""
    lat: list[float] = []
    t0 = time.monotonic()
    while not stop() and time.monotonic() - t0 < seconds:
        t = time.perf_counter()
        c.get(base + "/api/health")
        lat.append((time.perf_counter() - t) * 1e3)
        time.sleep(0.005)
    return lat


def _summary(lat: list[float]) -> str:
    lat = sorted(lat)

    def pct(p: float) -> float:
        return lat[min(len(lat) - 1, int(p / 100 * len(lat)))]

    return (
        f"{len(lat)} requests, p50 {pct(50):.1f} ms  p90 {pct(90):.1f} ms  "
        f"p99 {pct(99):.1f} ms  max {lat[-1]:.1f} ms"
    )


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--ops", type=int, default=20_000)
    a = ap.parse_args()
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    with tempfile.TemporaryDirectory() as tmp:
        exe = Path(sys.executable).with_name("modd-backend")
        proc = subprocess.Popen(
            [
                str(exe),
                "--port",
                str(port),
                "--data",
                tmp,
                "--scene-port",
                "-1",
                "--zenoh-connect",
                f"tcp/127.0.0.1:{free_port()}",
            ],
            env={**os.environ, "MODD_ADMIN_PASSWORD": PASSWORD},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            deadline = time.monotonic() + 120
            while True:
                try:
                    r = httpx.post(
                        base + "/api/auth/login",
                        timeout=5,
                        json={"username": "admin", "password": PASSWORD},
                    )
                    break
                except httpx.TransportError:
                    assert time.monotonic() < deadline and proc.poll() is None
                    time.sleep(0.2)
            token = r.json()["token"]
            with httpx.Client(timeout=30) as c:  # the same machine, no flood
                idle = _poll(c, base, lambda: False, seconds=3.0)
            ws = connect(f"ws://127.0.0.1:{port}/api/drones/usv/stream", open_timeout=10)
            ws.send(json.dumps({"op": "auth", "token": token}))
            ws.recv(timeout=10)
            done = threading.Event()
            drained = [0]

            def flood() -> None:
                for i in range(a.ops):
                    ws.send(json.dumps({"op": "subscribe", "subscriber": f"s_{i}"}))
                done.set()

            def drain() -> None:
                try:
                    while True:
                        ws.recv(timeout=2)
                        drained[0] += 1
                except Exception:  # closed or idle: the run is over
                    return

            threads = [threading.Thread(target=flood), threading.Thread(target=drain)]
            for t in threads:
                t.start()
            t0 = time.monotonic()
            with httpx.Client(timeout=30) as c:
                # until every op is sent and the server has answered or is idle
                lat = _poll(c, base, lambda: done.is_set() and not threads[1].is_alive())
            took = time.monotonic() - t0
            ws.close()
            for t in threads:
                t.join()
            print(f"health with no load: {_summary(idle)}")
            print(
                f"health during {a.ops} subscribe ops on one socket and their replies "
                f"({took:.1f} s, {drained[0]} replies read): {_summary(lat)}"
            )
        finally:
            proc.send_signal(signal.SIGTERM)
            proc.wait(30)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
