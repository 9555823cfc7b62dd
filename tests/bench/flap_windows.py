"""A link cut every 2 s for 60 s (issue 23, docs/reliability.md): how many of the 240
windows of a 0.25 s subscriber (scenario 1's sub_6) arrive live. The whole chain, real
processes on loopback: scenario 1 load -> PubBroker -> a TCP proxy whose connection is shut
down every PERIOD seconds -> SubBroker -> zenoh -> this script.

Run: .venv/bin/python tests/bench/flap_windows.py [SECONDS] [PERIOD_S]
"""

from __future__ import annotations

import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent / "subbroker"))

from flap_reconnect import Proxy  # noqa: E402
from modd.subbroker.payload import DeliveredValue  # noqa: E402
from modd.zenoh_session import client_settings, open_session, wait_connected  # noqa: E402
from subbroker_harness import (  # noqa: E402
    free_port,
    model_copy,
    processes,
    shared_credentials,
    start_load,
    start_pubbroker,
    start_subbroker,
    subbroker_config,
    wait_port,
)

SUBSCRIBER, PERIOD_NS = "sub_6", 250_000_000


def main() -> None:
    seconds = float(sys.argv[1]) if len(sys.argv) > 1 else 60.0
    period = float(sys.argv[2]) if len(sys.argv) > 2 else 2.0
    got: list[DeliveredValue] = []
    lock = threading.Lock()

    def on_sample(sample: Any) -> None:
        if str(sample.key_expr).endswith(f"/sub/{SUBSCRIBER}"):
            v = DeliveredValue.from_json(sample.payload.to_bytes())
            with lock:
                got.append(v)

    with tempfile.TemporaryDirectory(prefix="modd-flap-") as d:
        tmp = Path(d)
        link, ingress, zport = free_port(), free_port(), free_port()
        model = model_copy(tmp, "scenario1.modd")
        pb = start_pubbroker(tmp, model, link, ingress)
        proxy = Proxy(link)
        proxy.start()
        sb = start_subbroker(tmp, subbroker_config(tmp, model, proxy.port, zport))
        load = start_load(tmp, model, ingress, seconds + 40)
        with processes(pb, sb, load):
            wait_port(zport)
            if not sb.wait_log("running", 30):
                raise SystemExit("the SubBroker did not start: " + sb.log())
            session = open_session(
                client_settings(f"tcp/127.0.0.1:{zport}", shared_credentials().cred_file("backend"))
            )
            try:
                assert wait_connected(session, 10)
                session.declare_subscriber("modd/usv/**", on_sample)
                time.sleep(3)
                t0 = time.time_ns()
                cuts = 0
                while time.time_ns() - t0 < seconds * 1e9:
                    time.sleep(period)
                    proxy.cut()
                    cuts += 1
                t1 = t0 + int(seconds * 1e9)
                time.sleep(3)
            finally:
                session.close()  # type: ignore[no-untyped-call]
    with lock:
        live = {
            v.end_ns
            for v in got
            if t0 < v.end_ns <= t1 and not v.backfilled and v.value is not None
        }
    expected = int(seconds * 1e9) // PERIOD_NS
    print(
        f"link cut every {period:g} s for {seconds:g} s ({cuts} cuts): {len(live)} of "
        f"{expected} windows of {SUBSCRIBER} live"
    )


if __name__ == "__main__":
    main()
