"""Health during parallel CSV exports: N clients (two per user, as the
per-user limit allows) export a large archive topic as CSV again and again
while ``GET /api/health`` is polled every 10 ms; prints the health latency
percentiles and how the exports were answered (200, or 503/429 with
Retry-After past the heavy-route limits). A real ``modd-backend`` process on
loopback. Asserts nothing.

    .venv/bin/python tests/bench/bench_health_csv.py [--clients 70] [--seconds 20]

Target (issue 23): p99 <= 50 ms during 70 parallel CSV exports (was up to
20 s: health waited in the worker pool behind the exports).
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
from collections import Counter
from pathlib import Path

import httpx2 as httpx
from mcap.writer import Writer
from modd.ports import free_port

PASSWORD = "bench-admin-password"
TOPIC = "usv.accelerometer.accel_x"
T0 = 1_700_000_000_000_000_000


def write_archive(path: Path, samples: int) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    with path.open("wb") as f:
        w = Writer(f)
        w.start(profile="", library="bench")
        schema = w.register_schema(
            name="modd.float32",
            encoding="jsonschema",
            data=b'{"type":"object","properties":{"value":{"type":"number"}}}',
        )
        chan = w.register_channel(topic=TOPIC, message_encoding="json", schema_id=schema)
        for i in range(samples):
            t = T0 + i * 10_000_000
            w.add_message(
                chan,
                log_time=t,
                publish_time=t,
                data=json.dumps({"value": (i % 97) * 0.5}).encode(),
            )
        w.finish()  # type: ignore[no-untyped-call]


def start_backend(tmp: Path, port: int) -> subprocess.Popen[bytes]:
    exe = Path(sys.executable).with_name("modd-backend")
    return subprocess.Popen(
        [
            str(exe),
            "--port",
            str(port),
            "--data",
            str(tmp / "data"),
            "--no-zenoh",
            "--scene-port",
            "-1",
            "--foxglove-port",
            "0",
            "--archives",
            str(tmp / "archives"),
            "--frontend",
            str(tmp / "none"),
        ],
        env={**os.environ, "MODD_ADMIN_PASSWORD": PASSWORD},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def stop_backend(proc: subprocess.Popen[bytes]) -> None:
    proc.send_signal(signal.SIGTERM)
    try:
        proc.wait(30)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait(10)


def login(base: str, user: str, password: str) -> dict[str, str]:
    r = httpx.post(
        base + "/api/auth/login", timeout=30, json={"username": user, "password": password}
    )
    r.raise_for_status()
    return {"Authorization": f"Bearer {r.json()['token']}"}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--clients", type=int, default=70)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--samples", type=int, default=200_000, help="archive samples")
    a = ap.parse_args()
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        write_archive(tmp / "archives" / "usv" / "run-0000.mcap", a.samples)
        proc = start_backend(tmp, port)
        try:
            deadline = time.monotonic() + 120
            while True:
                try:
                    admin = login(base, "admin", PASSWORD)
                    break
                except httpx.TransportError:
                    assert time.monotonic() < deadline and proc.poll() is None
                    time.sleep(0.2)
            users = []
            for i in range((a.clients + 1) // 2):
                name, pw = f"sci{i}", f"bench-scientist-password-{i}"
                httpx.post(
                    base + "/api/users",
                    headers=admin,
                    timeout=30,
                    json={"username": name, "password": pw, "roles": ["scientist"]},
                ).raise_for_status()
                users.append(login(base, name, pw))
            stop = threading.Event()
            answers: Counter[int] = Counter()
            lock = threading.Lock()
            url = base + "/api/drones/usv/archives/run-0000.mcap/csv"

            def export(headers: dict[str, str]) -> None:
                with httpx.Client(timeout=120, headers=headers) as c:
                    while not stop.is_set():
                        r = c.get(url, params={"topic": TOPIC})
                        with lock:
                            answers[r.status_code] += 1
                        if r.status_code != 200:
                            stop.wait(float(r.headers.get("Retry-After", "1")))

            threads = [
                threading.Thread(target=export, args=(users[i // 2],)) for i in range(a.clients)
            ]
            for t in threads:
                t.start()
            time.sleep(1.0)  # every client has sent its first request
            lat = []
            end = time.monotonic() + a.seconds
            ready = Counter[str]()
            with httpx.Client(timeout=60) as c:
                while time.monotonic() < end:
                    t0 = time.perf_counter()
                    r = c.get(base + "/api/health")
                    lat.append((time.perf_counter() - t0) * 1e3)
                    ready["ready" if r.json().get("ready") else "saturated"] += 1
                    time.sleep(0.01)
            stop.set()
            for t in threads:
                t.join(180)
            lat.sort()

            def pct(p: float) -> float:
                return lat[min(len(lat) - 1, int(p / 100 * len(lat)))]

            print(
                f"health during {a.clients} parallel CSV exports of {a.samples:,} samples "
                f"({a.seconds:g} s, {len(lat)} health requests; readiness {dict(ready)}):"
            )
            print(
                f"  p50 {pct(50):.1f} ms  p90 {pct(90):.1f} ms  p99 {pct(99):.1f} ms  "
                f"max {lat[-1]:.1f} ms"
            )
            print(f"  exports answered: {dict(sorted(answers.items()))}")
        finally:
            stop_backend(proc)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
