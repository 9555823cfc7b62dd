"""Broker footprint at the paper's scenario loads, side by side in one run: the PubBroker
(archive on, aggregating, sending on the MoDD link to a SubBroker) against Mosquitto
(forwarding every sample to one MQTT connection per subscriber), both fed at the sensors'
rates (scenario 1: 75 samples/s, scenario 2: 475 samples/s) with their subscribers
connected. CPU % of one core from /proc/PID/stat (utime + stime over the run) and RSS
(VmRSS sampled every 0.5 s: median and peak). Asserts nothing.

    .venv/bin/python tests/bench/bench_footprint.py [--seconds 30] [--scenario 1|2 ...]

Targets (issue 4): PubBroker < 1 % of a core and < 10 MB at scenario 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from benchkit.footprint import Footprint  # noqa: E402
from benchkit.report import ratio, table  # noqa: E402
from benchkit.run import Run, measure  # noqa: E402
from benchkit.scenario import Scenario, load  # noqa: E402

NAMES = {"modd": "PubBroker", "mosquitto": "Mosquitto"}


def run(scenarios: list[int], seconds: float) -> list[tuple[Scenario, Run]]:
    return [
        (sc, measure(kind, sc, seconds, capture=False, footprint=True))
        for sc in map(load, scenarios)
        for kind in NAMES
    ]


def render(results: list[tuple[Scenario, Run]], seconds: float) -> str:
    rows: list[list[object]] = []
    by_scenario: dict[int, dict[str, Footprint]] = {}
    for sc, r in results:
        assert r.footprint is not None
        fp = by_scenario.setdefault(sc.number, {})[r.kind] = r.footprint
        rows.append(
            [
                f"scenario {sc.number} ({sc.samples_per_s:g} samples/s)",
                NAMES[r.kind],
                fp.cpu_percent,
                fp.cpu_seconds,
                fp.rss_median_kb / 1024,
                fp.rss_peak_kb / 1024,
                r.delivery.values_per_s,
            ]
        )
        fps = by_scenario[sc.number]
        if len(fps) == len(NAMES):
            rows.append(
                [
                    f"scenario {sc.number}",
                    "ratio PubBroker / Mosquitto",
                    ratio(fps["modd"].cpu_percent, fps["mosquitto"].cpu_percent),
                    "",
                    ratio(fps["modd"].rss_median_kb, fps["mosquitto"].rss_median_kb),
                    "",
                    "",
                ]
            )
    return f"Broker footprint at the scenario loads, {seconds:g} s per broker\n\n" + table(
        [
            "load",
            "broker",
            "CPU % of a core",
            "CPU-s",
            "RSS MB (median)",
            "RSS MB (peak)",
            "values/s delivered",
        ],
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
