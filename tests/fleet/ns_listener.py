"""A viewer at one station, run inside its namespace, until SIGTERM: every zenoh sample
under KEY (through zenoh's recovery, as the subscriber API: what a break in the mesh
kept from it is asked for again), one hex line each in OUT, and what the subscriber
API (``modd.subscriber``, which keeps each window once by its identity) gives, one
JSON line each in OUT.api."""

from __future__ import annotations

import argparse
import signal
import threading
from typing import Any

from modd.subbroker.payload import DeliveredValue
from modd.subscriber import Subscription
from modd.zenoh_auth import CredentialStore
from modd.zenoh_recovery import values_subscriber
from modd.zenoh_session import ZenohSettings, open_session, wait_connected


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("--connect", required=True)
    p.add_argument("--credentials", required=True)
    p.add_argument("--key", default="modd/*/sub/*")
    p.add_argument("--out", required=True)
    args = p.parse_args()
    creds = CredentialStore(args.credentials).credentials("viewer")
    settings = ZenohSettings(mode="client", connect=(args.connect,), credentials=creds)
    session = open_session(settings)
    assert wait_connected(session, 10)
    lock = threading.Lock()
    out = open(args.out, "a")  # noqa: SIM115 - closed at the end

    def on(sample: Any) -> None:
        with lock:
            out.write(sample.payload.to_bytes().hex() + "\n")
            out.flush()

    api = open(args.out + ".api", "a")  # noqa: SIM115 - closed at the end

    def given(value: DeliveredValue) -> None:
        with lock:
            api.write(value.to_json().decode() + "\n")
            api.flush()

    sub = values_subscriber(session, args.key, on)  # as the subscriber API: it recovers
    subscription = Subscription(session, args.key, given)
    print("listening", flush=True)
    done = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: done.set())
    done.wait()
    sub.undeclare()
    subscription.close()
    session.close()  # type: ignore[no-untyped-call]
    out.close()
    api.close()


if __name__ == "__main__":
    main()
