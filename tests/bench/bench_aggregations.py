"""Scenario 1 with MEDIAN, STDDEV or PERCENTILE(95) instead of AVERAGE (issue 45): link
bytes/s on the wire (tshark on lo, IP and TCP headers included) and the PubBroker's CPU per ingested
sample, each aggregation in turn at the same 25 Hz load. Asserts nothing; prints the
figures beside the planner's prediction.

    .venv/bin/python tests/bench/bench_aggregations.py [--seconds 20] [--json F]

The base station is the Python link codec (tests/runtime/pubbroker_harness.py), as in
bench_pubbroker.py; without tshark or capture rights the wire figures are skipped.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "tests" / p) for p in ("runtime", "subbroker", "bench")]

from bench_pubbroker import start_steady, wire_figures  # noqa: E402
from benchkit.capture import Capture  # noqa: E402
from benchkit.footprint import cpu_seconds  # noqa: E402
from pubbroker_harness import SCENARIOS  # noqa: E402

HZ = 25.0
#: The accumulator alone: ns per sample (add, and its share of take) for windows of n samples.
ACCUMULATOR_BENCH = r"""
#include <chrono>
#include <cmath>
#include <cstdio>
#include "modd/broker/accumulator.hpp"
using namespace modd;
int main() {
  static double xs[4096];
  for (int i = 0; i < 4096; ++i) xs[i] = std::sin(i * 0.37);
  const char* names[] = {"AVERAGE", "MEDIAN", "STDDEV", "RANGE", "PERCENTILE(95)"};
  link::Aggregation aggs[] = {link::Aggregation::Average, link::Aggregation::Median,
                              link::Aggregation::Stddev, link::Aggregation::Range,
                              link::Aggregation::Percentile};
  for (int n : {6, 50, 1000}) {
    for (int a = 0; a < 5; ++a) {
      broker::Accumulator acc(link::ValueType::Float32, aggs[a], 95);
      const long total = 20000000;
      double sink = 0;
      auto t0 = std::chrono::steady_clock::now();
      for (long i = 0; i < total; ++i) {
        acc.add(xs[i & 4095], 0);
        if (i % n == n - 1) sink += acc.take().number;
      }
      double ns = std::chrono::duration<double, std::nano>(std::chrono::steady_clock::now() - t0)
                      .count() / total;
      std::printf("%s %d %.2f %g\n", names[a], n, ns, sink);
    }
  }
}
"""


def accumulator_ns(tmp: Path) -> list[dict[str, Any]]:
    """ns per sample of the C++ accumulator alone (-O2), samples from a table."""
    src, exe = tmp / "acc_bench.cpp", tmp / "acc_bench"
    src.write_text(ACCUMULATOR_BENCH)
    cpp = REPO / "runtime" / "cpp"
    subprocess.run(
        [
            "c++",
            "-O2",
            "-std=c++20",
            f"-I{cpp / 'include'}",
            str(src),
            str(cpp / "src" / "broker" / "accumulator.cpp"),
            "-o",
            str(exe),
        ],
        check=True,
    )
    out = subprocess.run([str(exe)], check=True, capture_output=True, text=True).stdout
    return [
        {"aggregation": a, "window_samples": int(n), "ns_per_sample": float(ns)}
        for a, n, ns, _ in (line.split() for line in out.splitlines())
    ]


def _plan(aggregation: str) -> Any:
    from modd_model import load_model
    from modd_plan import make_plan

    model = load_model(SCENARIOS / "scenario1.modd")
    name, _, p = aggregation.partition("(")
    for sub in model["subscribers"]:
        if sub["aggregation"] == "AVERAGE":
            sub["aggregation"] = name
            if p:
                sub["percentile"] = float(p.rstrip(")"))
    return make_plan(model)


def run(tmp: Path, aggregation: str, seconds: float) -> dict[str, Any]:
    """One aggregation's steady state: wire figures, CPU per sample, the plan's bytes/s."""
    from modd.subbroker.planning import config_for

    plan = _plan(aggregation)
    config = config_for(plan, 1, 30)
    b, base, stop, loader = start_steady(tmp, config, seconds, 30)
    assert b.proc is not None
    capture = shutil.which("tshark") is not None and os.geteuid() == 0
    cap = Capture(tmp, b.link_port, seconds) if capture else None
    cpu0, t0 = cpu_seconds(b.proc.pid), time.monotonic()
    time.sleep(seconds)
    cpu, wall = cpu_seconds(b.proc.pid) - cpu0, time.monotonic() - t0
    wire = wire_figures(cap.wait()) if cap else "skipped: tshark missing or no capture rights"
    stop.set()
    loader.join()
    base.close()
    b.stop()
    samples = HZ * len(config.topics) * wall
    return {
        "aggregation": aggregation,
        "planner_drone_to_base_bytes_per_s": round(plan.link.drone_to_base, 1),
        "wire": wire,
        "cpu_percent": round(100 * cpu / wall, 3),
        "cpu_us_per_sample": round(1e6 * cpu / samples, 2),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--json", type=Path, default=REPO / "build" / "bench" / "aggregations.json")
    args = ap.parse_args()
    results = []
    print(f"== Scenario 1, AVERAGE subscriptions replaced, {args.seconds:.0f} s each, {HZ:g} Hz")
    with tempfile.TemporaryDirectory() as d:
        for aggregation in ("AVERAGE", "MEDIAN", "STDDEV", "PERCENTILE(95)"):
            (Path(d) / aggregation.partition("(")[0]).mkdir()
            r = run(Path(d) / aggregation.partition("(")[0], aggregation, args.seconds)
            results.append(r)
            w = r["wire"]
            wire = (
                f"drone->base {w['drone_to_base']['bytes_per_s']} B/s"
                if isinstance(w, dict)
                else f"wire {w}"
            )
            print(
                f"  {aggregation:14s} {wire} | planner {r['planner_drone_to_base_bytes_per_s']}"
                f" B/s | PubBroker CPU {r['cpu_percent']} % of a core,"
                f" {r['cpu_us_per_sample']} µs per sample"
            )
        alone = accumulator_ns(Path(d))
    print("== The C++ accumulator alone (-O2), ns per sample (add, and take per window)")
    for n in sorted({r["window_samples"] for r in alone}):
        row = [
            f"{r['aggregation']} {r['ns_per_sample']:.1f}"
            for r in alone
            if r["window_samples"] == n
        ]
        print(f"  windows of {n:4d} samples: " + ", ".join(row))
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"scenario1": results, "accumulator": alone}, indent=1))
    print(f"figures written to {args.json}")


if __name__ == "__main__":
    main()
