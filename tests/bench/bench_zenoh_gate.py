"""What the SubBroker's zenoh accept gate (modd.zenoh_gate) costs a viewer: a router with
the SubBroker's authentication publishes, in this process (as the SubBroker does, gate
thread included), to a viewer in another process connected through the gate or straight
to zenoh; prints, for each, the latency of 64-byte values at 500 a second (p50, p99) and
the throughput of 16 KiB values sent as fast as zenoh's blocking congestion control
lets them. Asserts nothing.

    .venv/bin/python tests/bench/bench_zenoh_gate.py [--seconds 4]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import zenoh
from modd.ports import free_port
from modd.zenoh_auth import CredentialStore
from modd.zenoh_gate import start_gates
from modd.zenoh_gate_policy import GateLimits
from modd.zenoh_session import ZenohSettings, open_session, secured

KEY = "modd/usv/sub/bench"
VIEWER = r"""
import json, sys, time, threading
from modd.zenoh_session import client_settings, open_session, wait_connected
s = open_session(client_settings(sys.argv[1], sys.argv[2]))
assert wait_connected(s, 10)
lat, n, size, first, last, done = [], 0, 0, None, None, threading.Event()
def on(sample):
    global n, size, first, last
    now = time.time()
    b = sample.payload.to_bytes()
    if b == b"end":
        done.set(); return
    sent = float(b[:20].decode())
    n += 1; size += len(b); first = first or now; last = now
    lat.append(now - sent)
s.declare_subscriber(sys.argv[3], on)
print("ready", flush=True)
done.wait(120)
lat.sort()
q = lambda p: lat[min(len(lat) - 1, int(p * len(lat)))] * 1e3 if lat else None
span = (last - first) if n > 1 else None
print(json.dumps({"n": n, "p50_ms": q(0.5), "p99_ms": q(0.99),
                  "mb_s": size / span / 1e6 if span else None}), flush=True)
s.close()
"""


def measure(gated: bool, seconds: float, size: int, rate: float | None) -> dict[str, object]:
    store = CredentialStore(Path(tempfile.mkdtemp(prefix="modd-gb-")) / "credentials")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    settings = secured(ZenohSettings(mode="router", listen=(endpoint,)), store, "subbroker", "usv")
    if not gated:
        settings = replace(settings, gate=GateLimits(enabled=False))
    inner, gates = start_gates(settings)
    router = open_session(inner)
    viewer = subprocess.Popen(
        [sys.executable, "-c", VIEWER, endpoint, str(store.cred_file("viewer")), KEY],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert viewer.stdout is not None and viewer.stdout.readline().strip() == "ready"
        time.sleep(0.5)
        pub = router.declare_publisher(KEY, congestion_control=zenoh.CongestionControl.BLOCK)
        _publish(pub, seconds, size, rate)
        time.sleep(0.5)
        pub.put(b"end")
        return dict(json.loads(viewer.stdout.readline()))
    finally:
        viewer.wait(30)
        router.close()  # type: ignore[no-untyped-call]
        for g in gates:
            g.stop()


def _publish(pub: zenoh.Publisher, seconds: float, size: int, rate: float | None) -> None:
    end = time.monotonic() + seconds
    pad = b"x" * max(0, size - 20)
    n = 0
    start = time.monotonic()
    while time.monotonic() < end:
        pub.put(f"{time.time():<20.6f}".encode() + pad)
        n += 1
        if rate:
            time.sleep(max(0.0, start + n / rate - time.monotonic()))


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seconds", type=float, default=4.0)
    a = p.parse_args()
    for gated in (False, True):
        lat = measure(gated, a.seconds, 64, 500.0)
        thr = measure(gated, a.seconds, 16384, None)
        name = "through the gate" if gated else "straight to zenoh"
        print(
            f"{name:18}: 64 B at 500/s: p50 {lat['p50_ms']:.3f} ms, p99 {lat['p99_ms']:.3f} ms "
            f"({lat['n']} values); 16 KiB flat out: {thr['mb_s']:.1f} MB/s ({thr['n']} values)",
            flush=True,
        )


if __name__ == "__main__":
    main()
