"""Delivery latency side by side in one run, at the paper's scenario loads, on loopback:

- MoDD link: from the end of a window (the slot date the planner gives: config epoch +
  slot time, on the drone's clock) to receipt at a base-station subscriber through
  ``modd.subscribe`` (PubBroker -> link -> SubBroker -> zenoh);
- Mosquitto: MQTT publish -> delivery (the publisher's stamp in the 16-byte payload to
  receipt at the paho subscriber), the paper's Table V definition for MQTT;
- zenoh downsampling: publish -> delivery at the base-side zenoh subscriber.

All clocks are this machine's, so no clock offset enters. p50 and p99 over every value
delivered in ``--seconds`` (after the systems settle). Asserts nothing.

    .venv/bin/python tests/bench/bench_latency.py [--seconds 30] [--scenario 1|2 ...]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchkit.report import table  # noqa: E402
from benchkit.run import Run, measure  # noqa: E402
from benchkit.scenario import Scenario, load  # noqa: E402

DEFINITION = {
    "modd": "window end → delivery",
    "mosquitto": "publish → delivery",
    "zenoh": "publish → delivery",
}
PAPER = {"modd": "modd", "mosquitto": "mqtt"}
SYSTEMS = ("modd", "mosquitto", "zenoh")


def run(scenarios: list[int], seconds: float) -> list[tuple[Scenario, Run]]:
    return [
        (sc, measure(kind, sc, seconds, capture=False, footprint=False))
        for sc in map(load, scenarios)
        for kind in SYSTEMS
    ]


def render(results: list[tuple[Scenario, Run]], seconds: float) -> str:
    rows: list[list[object]] = []
    for sc, r in results:
        d = r.delivery
        paper = sc.paper["paper_latency_s"].get(PAPER.get(r.kind, ""))
        rows.append(
            [
                f"scenario {sc.number}",
                r.system,
                DEFINITION[r.kind],
                len(d.latencies_ns),
                d.latency_ms(0.5),
                d.latency_ms(0.99),
                d.latency_ms(1.0),
                f"{paper * 1000:,.0f}" if paper is not None else "—",
            ]
        )
    return f"Delivery latency on loopback, {seconds:g} s per system\n\n" + table(
        ["load", "system", "from → to", "values", "p50 ms", "p99 ms", "max ms", "paper Table V ms"],
        rows,
    )


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--scenario", type=int, choices=(1, 2), action="append")
    args = ap.parse_args(argv)
    print(render(run(args.scenario or [1, 2], args.seconds), args.seconds))
    return 0


if __name__ == "__main__":
    sys.exit(main())
