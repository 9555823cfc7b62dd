"""Health and saves under ordinary editing load: E editors save their
projects in a loop (read the head, change the link, save on it, wait
``--think`` seconds), V viewers
hold a stream WebSocket each (watching a project: every save is announced to
them), X clients export CSV of an archive, and one user holds S extra
sockets (the per-user cap refuses those past it; another user than the editors); meanwhile
``GET /api/health`` is polled every 10 ms. Prints the health and save
latency percentiles, and how the sockets and exports were answered. A real
``modd-backend`` process on loopback (SQLite, or ``--database-url``).
Asserts nothing.

    .venv/bin/python tests/bench/bench_health_editing.py [--editors 50] [--viewers 10]
        [--exporters 4] [--sockets 0] [--seconds 20] [--think 1] [--database-url URL]

Target (issue 30): health p99 <= 50 ms and save p99 <= 500 ms on SQLite under
50 editors, 10 viewers and 4 exporters (was 442-818 ms for health); with
1,000 sockets of one user, save p50 within 20 % of the run without.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter
from pathlib import Path
from typing import Any

import httpx2 as httpx
from bench_health_csv import PASSWORD, TOPIC, login, stop_backend, write_archive
from bench_health_ws import _poll
from modd.ports import free_port
from websockets.sync.client import ClientConnection, connect

DEMO = Path(__file__).resolve().parents[2] / "metamodel" / "examples" / "demo.modd"


def pct(lat: list[float], p: float) -> float:
    s = sorted(lat)
    return s[min(len(s) - 1, int(p / 100 * len(s)))] if s else float("nan")


def summary(lat: list[float]) -> str:
    return (
        f"{len(lat)} requests, p50 {pct(lat, 50):.1f} ms  p90 {pct(lat, 90):.1f} ms  "
        f"p99 {pct(lat, 99):.1f} ms  max {max(lat, default=float('nan')):.1f} ms"
    )


class Load:
    """The clients of one run; every list is appended to under ``lock``."""

    def __init__(self, base: str, admin: dict[str, str], think_s: float) -> None:
        self.base, self.admin, self.think_s = base, admin, think_s
        self.stop = threading.Event()
        self.lock = threading.Lock()
        self.saves: list[float] = []
        self.answers: Counter[str] = Counter()

    def count(self, what: str) -> None:
        with self.lock:
            self.answers[what] += 1

    def editor(self, pid: int) -> None:
        url = f"{self.base}/api/projects/{pid}/model"
        with httpx.Client(timeout=120, headers=self.admin) as c:
            i = 0
            while not self.stop.is_set():
                head = c.get(url).json()
                model = dict(
                    head["model"], link=dict(head["model"].get("link") or {}, maxBuffer=1000 + i)
                )
                t0 = time.perf_counter()
                r = c.put(url, json={"model": model, "base_revision": head["revision"]})
                took = (time.perf_counter() - t0) * 1e3
                self.count(f"save {r.status_code}")
                if r.status_code == 200:
                    with self.lock:
                        self.saves.append(took)
                i += 1
                self.stop.wait(self.think_s)

    def start(
        self, port: int, token: str, pids: list[int], viewers: int, exporters: int
    ) -> list[threading.Thread]:
        """One editor per project, ``viewers`` and ``exporters`` (as the
        admin), started; returns once every client is at work."""
        threads = [threading.Thread(target=self.editor, args=(p,)) for p in pids]
        threads += [
            threading.Thread(target=self.viewer, args=(port, token, pids[i % len(pids)]))
            for i in range(viewers)
        ]
        threads += [
            threading.Thread(target=self.exporter, args=(self.admin,)) for _ in range(exporters)
        ]
        for t in threads:
            t.start()
        time.sleep(2.0)
        return threads

    def viewer(self, port: int, token: str, pid: int) -> None:
        try:
            ws = connect(f"ws://127.0.0.1:{port}/api/drones/usv/stream", open_timeout=30)
            ws.send(json.dumps({"op": "auth", "token": token}))
            ws.send(json.dumps({"op": "watch", "project": pid}))
            while not self.stop.is_set():
                try:
                    ws.recv(timeout=1)
                    self.count("viewer messages")
                except TimeoutError:
                    continue
            ws.close()
        except Exception as exc:  # reported, not raised: a bench asserts nothing
            self.count(f"viewer error {type(exc).__name__}")

    def exporter(self, headers: dict[str, str]) -> None:
        url = f"{self.base}/api/drones/usv/archives/run-0000.mcap/csv"
        with httpx.Client(timeout=120, headers=headers) as c:
            while not self.stop.is_set():
                r = c.get(url, params={"topic": TOPIC})
                self.count(f"csv {r.status_code}")
                if r.status_code != 200:
                    self.stop.wait(float(r.headers.get("Retry-After", "1")))


def hold_sockets(port: int, token: str, n: int, load: Load) -> list[ClientConnection]:
    """``n`` stream sockets of one user: opened ones are kept, refusals counted."""
    held = []
    for _ in range(n):
        try:
            ws = connect(f"ws://127.0.0.1:{port}/api/drones/usv/stream", open_timeout=30)
            ws.send(json.dumps({"op": "auth", "token": token}))
            ws.send(json.dumps({"op": "ping"}))
            ws.recv(timeout=30)  # authenticated
            ws.recv(timeout=30)  # pong, or the cap's close (4429)
            held.append(ws)
            load.count("socket opened")
        except Exception:  # closed by the cap (4429)
            load.count("socket refused")
    return held


def run(a: argparse.Namespace, tmp: Path) -> None:
    port = free_port()
    base = f"http://127.0.0.1:{port}"
    write_archive(tmp / "archives" / "usv" / "run-0000.mcap", a.samples)
    proc = start(tmp, port, a.database_url)
    try:
        admin = wait_login(base, proc)
        with httpx.Client(timeout=30) as c:
            idle = _poll(c, base, lambda: False, seconds=3.0)
        text = DEMO.read_text()
        pids = [
            httpx.post(
                f"{base}/api/projects",
                headers=admin,
                timeout=60,
                json={"name": f"p{i}", "model": {"text": text}},
            ).json()["id"]
            for i in range(a.editors)
        ]
        load = Load(base, admin, a.think)
        token = admin["Authorization"][7:]
        httpx.post(
            f"{base}/api/users",
            headers=admin,
            timeout=60,
            json={"username": "crowd", "password": PASSWORD, "roles": ["scientist"]},
        )
        crowd = login(base, "crowd", PASSWORD)["Authorization"][7:]
        held = hold_sockets(port, crowd, a.sockets, load)
        threads = load.start(port, token, pids, a.viewers, a.exporters)
        with httpx.Client(timeout=60) as c:
            lat = _poll(c, base, lambda: False, seconds=a.seconds)
        load.stop.set()
        for t in threads:
            t.join(180)
        for ws in held:
            ws.close()
        db = "PostgreSQL" if a.database_url else "SQLite"
        print(
            f"{db}: {a.editors} editors (a save every {a.think:g} s + its answer), "
            f"{a.viewers} viewers, {a.exporters} CSV exporters, {a.sockets} extra sockets "
            f"of one user, {a.seconds:g} s"
        )
        print(f"  health idle:       {summary(idle)}")
        print(f"  health under load: {summary(lat)}")
        print(f"  saves:             {summary(load.saves)}")
        print(f"  answers: {dict(sorted(load.answers.items()))}")
    finally:
        stop_backend(proc)


def start(tmp: Path, port: int, database_url: str | None, cores: str | None = None) -> Any:
    """The backend, pinned to ``cores`` (a taskset list) when given."""
    exe = Path(sys.executable).with_name("modd-backend")
    extra = ["--database-url", database_url] if database_url else []
    pin = ["taskset", "-c", cores] if cores else []
    return subprocess.Popen(
        [
            *pin,
            str(exe),
            "--port",
            str(port),
            "--data",
            str(tmp / "data"),
            "--scene-port",
            "-1",
            "--foxglove-port",
            "0",
            "--foxglove-replay-port",
            "0",
            "--zenoh-connect",
            f"tcp/127.0.0.1:{free_port()}",
            "--archives",
            str(tmp / "archives"),
            "--frontend",
            str(tmp / "none"),
            *extra,
        ],
        env={**os.environ, "MODD_ADMIN_PASSWORD": PASSWORD},
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )


def wait_login(base: str, proc: Any) -> dict[str, str]:
    deadline = time.monotonic() + 120
    while True:
        try:
            return login(base, "admin", PASSWORD)
        except httpx.TransportError:
            assert time.monotonic() < deadline and proc.poll() is None, "no backend"
            time.sleep(0.2)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--editors", type=int, default=50)
    ap.add_argument("--viewers", type=int, default=10)
    ap.add_argument("--exporters", type=int, default=4)
    ap.add_argument("--sockets", type=int, default=0)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument(
        "--think",
        type=float,
        default=1.0,
        help="seconds an editor waits between saves (a person editing)",
    )
    ap.add_argument("--samples", type=int, default=200_000, help="archive samples")
    ap.add_argument("--database-url")
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmpdir:
        run(a, Path(tmpdir))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
