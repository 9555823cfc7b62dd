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

from benchkit.report import ratio, table  # noqa: E402
from benchkit.run import measure  # noqa: E402
from benchkit.scenario import load  # noqa: E402

NAMES = {"modd": "PubBroker", "mosquitto": "Mosquitto"}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--scenario", type=int, choices=(1, 2), action="append")
    args = ap.parse_args(argv)
    rows: list[list[object]] = []
    for n in args.scenario or [1, 2]:
        sc = load(n)
        fps = {}
        for kind in ("modd", "mosquitto"):
            r = measure(kind, sc, args.seconds, capture=False, footprint=True)
            assert r.footprint is not None
            fps[kind] = fp = r.footprint
            rows.append([f"scenario {n} ({sc.samples_per_s:g} samples/s)", NAMES[kind],
                         fp.cpu_percent, fp.cpu_seconds, fp.rss_median_kb / 1024,
                         fp.rss_peak_kb / 1024, r.delivery.values_per_s])
        rows.append([f"scenario {n}", "ratio PubBroker / Mosquitto",
                     ratio(fps["modd"].cpu_percent, fps["mosquitto"].cpu_percent), "",
                     ratio(fps["modd"].rss_median_kb, fps["mosquitto"].rss_median_kb), "", ""])
    print(f"Broker footprint at the scenario loads, {args.seconds:g} s per broker\n")
    print(table(["load", "broker", "CPU % of a core", "CPU-s", "RSS MB (median)",
                 "RSS MB (peak)", "values/s delivered"], rows))
    return 0


if __name__ == "__main__":
    sys.exit(main())
