"""Backend live-plan benchmark: the latency of ``POST /api/plan`` for the
paper's scenarios, through a real ``modd-backend`` process on loopback (HTTP,
JSON encoding, auth and the planner included), for .modd text and JSON input
and both buffer-size methods. Prints figures; asserts nothing about time.

    .venv/bin/python tests/bench/bench_backend_plan.py [--runs N]

Target (issue 7): under 300 ms per request for the paper's scenarios.
"""

from __future__ import annotations

import argparse
import os
import signal
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx2 as httpx
from modd.ports import free_port
from modd_model import load_model

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO.parent / "shared" / "scenarios"
PASSWORD = "bench-admin-password"




def start_backend(data: Path, port: int) -> subprocess.Popen[bytes]:
    exe = Path(sys.executable).with_name("modd-backend")
    log = (data / "backend.log").open("wb")
    proc = subprocess.Popen(
        [str(exe), "--host", "127.0.0.1", "--port", str(port), "--data", str(data),
         "--no-zenoh", "--admin-password", PASSWORD],
        stdout=log, stderr=subprocess.STDOUT,
    )
    log.close()
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:
        try:
            httpx.get(f"http://127.0.0.1:{port}/openapi.json", timeout=1)
            return proc
        except httpx.TransportError:
            time.sleep(0.1)
    os.kill(proc.pid, signal.SIGTERM)
    raise RuntimeError("the backend did not start: " + (data / "backend.log").read_text())


def measure(client: httpx.Client, body: dict[str, object], method: str, runs: int) -> list[float]:
    times = []
    for _ in range(runs):
        start = time.perf_counter()
        r = client.post(f"/api/plan?method={method}", json=body)
        times.append((time.perf_counter() - start) * 1000)
        r.raise_for_status()
        assert r.json()["ok"], r.text
    return times


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser()
    p.add_argument("--runs", type=int, default=50)
    args = p.parse_args(argv)
    port = free_port()
    with tempfile.TemporaryDirectory() as tmp:
        proc = start_backend(Path(tmp), port)
        try:
            with httpx.Client(base_url=f"http://127.0.0.1:{port}", timeout=30) as c:
                login = c.post("/api/auth/login", json={"username": "admin", "password": PASSWORD})
                c.headers["Authorization"] = f"Bearer {login.json()['token']}"
                print(f"POST /api/plan, {args.runs} requests each, modd-backend on loopback")
                print(f"{'scenario':<10} {'input':<5} {'method':<6} "
                      f"{'median ms':>9} {'p95 ms':>7} {'max ms':>7}")
                for name in ("scenario1", "scenario2"):
                    path = SCENARIOS / f"{name}.modd"
                    bodies = {"modd": {"text": path.read_text()},
                              "json": {"model": load_model(path)}}
                    for kind, body in bodies.items():
                        for method in ("exact", "cvxpy"):
                            measure(c, body, method, 3)  # warm-up
                            t = sorted(measure(c, body, method, args.runs))
                            p95 = t[max(0, int(len(t) * 0.95) - 1)]
                            print(f"{name:<10} {kind:<5} {method:<6} "
                                  f"{statistics.median(t):>9.1f} {p95:>7.1f} {t[-1]:>7.1f}")
        finally:
            os.kill(proc.pid, signal.SIGTERM)
            proc.wait(10)
    return 0


if __name__ == "__main__":
    sys.exit(main())
