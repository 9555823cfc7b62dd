"""The fleet benchmark's subscriber, run in its own namespace until SIGTERM: every raw
zenoh sample under KEY, one line each in OUT: its receipt time (ns, this machine's
clock, which the namespaces share with the drones'), drone, subscriber, epoch, window,
the window's end (ns) and whether it was backfilled.

    python fleet_viewer.py --connect tcp/10.44.1.1:7447 --credentials DIR --out FILE
"""

from __future__ import annotations

import argparse
import json
import signal
import threading
import time
from typing import Any

from modd.subbroker.payload import DeliveredValue
from modd.zenoh_auth import CredentialStore
from modd.zenoh_session import ZenohSettings, open_session, wait_connected


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--connect", required=True)
    p.add_argument("--credentials", required=True)
    p.add_argument("--key", default="modd/*/sub/*")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    creds = CredentialStore(args.credentials).credentials("viewer")
    session = open_session(ZenohSettings(mode="client", connect=(args.connect,), credentials=creds))
    assert wait_connected(session, 30)
    lock = threading.Lock()
    out = open(args.out, "a")  # noqa: SIM115 - closed at the end

    def on(sample: Any) -> None:
        now = time.time_ns()
        raw = sample.payload.to_bytes()
        if not raw.startswith(b"{"):
            return
        v = DeliveredValue.from_json(raw)
        row = [now, v.drone, v.subscriber, v.epoch_ns, v.window, v.end_ns, v.backfilled]
        with lock:
            out.write(json.dumps(row) + "\n")

    sub = session.declare_subscriber(args.key, on)
    print("listening", flush=True)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    done.wait()
    sub.undeclare()  # type: ignore[no-untyped-call]
    session.close()  # type: ignore[no-untyped-call]
    with lock:
        out.close()


if __name__ == "__main__":
    main()
