"""Link bytes on the wire, side by side in one run: the paper's scenarios 1 and 2, each
system in turn at the same load (publishers at the sensors' rates), tshark on ``lo`` with a
port filter summing the IP length per direction (IP and TCP headers included), data
segments and pure ACKs apart:

- MoDD link: this project's PubBroker -> SubBroker TCP link (real binaries, configs from
  the scenario; 4 B values aggregated per window, one frame per schedule slot);
- Mosquitto (Debian's) on the drone: every sample as a QoS 0 PUBLISH (16-byte payload), one
  MQTT connection per subscriber from the base; the link is broker <-> subscribers;
- zenoh: a drone-side router with egress downsampling per subscriber key at the
  subscription's rate, base-side subscribers. It DROPS samples to reach the rate; it does
  not aggregate (a subscriber asking MIN over 1 s gets one raw sample, not the minimum);

beside the planner's prediction (modd_plan.make_plan) and the information floor (values
the subscribers need per second x 4 B + one 52-byte TCP segment per slot). Asserts
nothing; prints the targets (scenario 1 <= 300 B/s, scenario 2 <= 140 B/s drone -> base).

    .venv/bin/python tests/bench/bench_link.py [--seconds 60] [--scenario 1|2 ...]
                                               [--system modd|mosquitto|zenoh ...] [--json F]

Needs tshark and mosquitto (scripts/setup.sh installs both) and root to capture on lo.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchkit.report import fmt, ratio, table  # noqa: E402
from benchkit.run import Run, measure  # noqa: E402
from benchkit.scenario import Scenario, load  # noqa: E402

TARGETS = {1: 300.0, 2: 140.0}  # drone -> base, B/s (issues 5 and 10)
SYSTEM_ORDER = ("modd", "mosquitto", "zenoh")


def rows(sc: Scenario, runs: list[Run]) -> list[list[object]]:
    out: list[list[object]] = []
    for r in runs:
        assert r.wire is not None
        d, u = r.wire.rates()["drone_to_base"], r.wire.rates()["base_to_drone"]
        out.append(
            [
                r.system,
                d["bytes_per_s"],
                d["packets_per_s"],
                f"{fmt(d['data_bytes_per_s'])} / {fmt(d['ack_bytes_per_s'])}",
                u["bytes_per_s"],
                u["packets_per_s"],
                f"{fmt(u['data_bytes_per_s'])} / {fmt(u['ack_bytes_per_s'])}",
                r.delivery.values_per_s,
                ratio(d["bytes_per_s"], sc.paper_modd_down),
                ratio(d["bytes_per_s"], sc.floor_down),
            ]
        )
    out.append(
        [
            "planner prediction",
            sc.planned_down,
            sc.slots_per_s,
            "",
            sc.planned_up,
            sc.slots_per_s,
            "",
            "",
            ratio(sc.planned_down, sc.paper_modd_down),
            ratio(sc.planned_down, sc.floor_down),
        ]
    )
    out.append(
        [
            "information floor",
            sc.floor_down,
            sc.slots_per_s,
            "",
            "",
            "",
            "",
            sc.sent_values_per_s,
            ratio(sc.floor_down, sc.paper_modd_down),
            "1.00×",
        ]
    )
    out.append(
        [
            "paper, MoDD",
            sc.paper_modd_down,
            "",
            "",
            "",
            "",
            "",
            "",
            "1.00×",
            ratio(sc.paper_modd_down, sc.floor_down),
        ]
    )
    mqtt = float(sc.paper["paper_bytes_per_s"]["drone_to_subscribers_mqtt"])
    out.append(
        [
            "paper, MQTT (to subscribers)",
            mqtt,
            "",
            "",
            "",
            "",
            "",
            "",
            ratio(mqtt, sc.paper_modd_down),
            ratio(mqtt, sc.floor_down),
        ]
    )
    return out


HEADER = [
    "system",
    "drone→base B/s",
    "pkt/s",
    "data / ACK B/s",
    "base→drone B/s",
    "pkt/s",
    "data / ACK B/s",
    "values/s delivered",
    "× paper MoDD",
    "× floor",
]


def summary(run: Run) -> dict[str, Any]:
    return {
        "system": run.system,
        "seconds": run.seconds,
        "wire": run.wire.rates() if run.wire else None,
        "delivered_per_subscriber": run.delivery.per_subscriber,
    }


def run(
    scenarios: list[int], systems: list[str], seconds: float
) -> list[tuple[Scenario, list[Run]]]:
    """Each scenario, each system in turn, ``seconds`` of capture each."""
    return [
        (sc, [measure(k, sc, seconds, footprint=False) for k in systems])
        for sc in map(load, scenarios)
    ]


def render(results: list[tuple[Scenario, list[Run]]], seconds: float) -> str:
    out = [
        f"Link bytes on the wire: loopback, tshark, IP bytes (headers included), "
        f"{seconds:g} s of steady state per system"
    ]
    for sc, runs in results:
        out.append(
            f"\n## Scenario {sc.number}: {len(sc.subscriptions)} subscriptions, "
            f"{sc.samples_per_s:g} samples/s published; target drone→base "
            f"≤ {TARGETS[sc.number]:g} B/s for the MoDD link\n"
        )
        out.append(table(HEADER, rows(sc, runs)))
        for r in runs:
            if r.system.startswith("zenoh"):
                asked = sum(1 / float(s.period_s) for s in sc.subscriptions)
                out.append(
                    f"\nzenoh: {r.delivery.values_per_s:.2f} values/s delivered for "
                    f"the {asked:.2f} windows/s asked: the interceptor drops samples "
                    "(it forwards the first one at least 1/freq after the last one "
                    "forwarded) and does not aggregate: a MIN/MAX/AVERAGE subscriber "
                    "gets one raw sample per window, not its aggregate."
                )
    return "\n".join(out)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0)
    ap.add_argument("--scenario", type=int, choices=(1, 2), action="append")
    ap.add_argument("--system", choices=SYSTEM_ORDER, action="append")
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    systems = [s for s in SYSTEM_ORDER if s in (args.system or SYSTEM_ORDER)]
    results = run(args.scenario or [1, 2], systems, args.seconds)
    print(render(results, args.seconds))
    if args.json:
        args.json.parent.mkdir(parents=True, exist_ok=True)
        args.json.write_text(
            json.dumps(
                {f"scenario{sc.number}": [summary(r) for r in runs] for sc, runs in results},
                indent=1,
            )
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
