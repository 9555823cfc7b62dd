"""An ON_CHANGE subscription against the periodic LAST it replaces (issue 45, item 5): one
subscription at 1 s on a slowly varying water temperature (15 °C, ±0.4 °C over 5 min,
a few mK of noise, 25 Hz), LAST, then ON_CHANGE(0.05) at most 2 events a window; and
ON_CHANGE's worst case, a signal flapping 14/16 °C at every sample (every sample an
event, coalesced beyond N = 2). Link bytes/s drone -> base on the wire (tshark on lo,
IP and TCP headers included, the keep-alive PING/PONG too) beside the planner's
estimate and its "at most" bound; the flapping run must stay within the bound.

    .venv/bin/python tests/bench/bench_events.py [--seconds 30] [--json F]

The base station is the Python link codec (tests/runtime/pubbroker_harness.py), as in
bench_aggregations.py; without tshark or capture rights the wire figures are skipped.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

REPO = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(REPO / "tests" / p) for p in ("runtime", "subbroker", "bench")]

from bench_pubbroker import start_steady, wire_figures  # noqa: E402
from benchkit.capture import Capture  # noqa: E402
from pubbroker_harness import SCENARIOS, f32  # noqa: E402

TOPIC = "usv.accelerometer.accel_x"  # the scenario's topic, read as a water temperature
ON_CHANGE = {"aggregation": "ON_CHANGE", "deadband": 0.05, "maxEvents": 2}
CASES: list[tuple[str, dict[str, Any], str]] = [
    ("LAST, slow temperature", {"aggregation": "LAST"}, "slow"),
    ("ON_CHANGE(0.05, 2), slow temperature", ON_CHANGE, "slow"),
    ("ON_CHANGE(0.05, 2), flapping 14/16", ON_CHANGE, "flapping"),
]


def slow(_topic: int, k: int) -> float:
    """15 °C, ±0.4 °C over a 5-minute period, ±2 mK of noise: k-th sample at 25 Hz."""
    return float(
        f32(15 + 0.4 * math.sin(2 * math.pi * k / (25 * 300)) + 0.002 * math.sin(0.37 * k))
    )


def flapping(_topic: int, k: int) -> float:
    return 14.0 if k % 2 else 16.0


def _plan(sub: dict[str, Any]) -> Any:
    from modd_model import load_model
    from modd_plan import make_plan

    model = load_model(SCENARIOS / "scenario1.modd")
    model["subscribers"] = [{"name": "temp", "topic": TOPIC, "periodS": "1.0", **sub}]
    return make_plan(model)


def run(tmp: Path, sub: dict[str, Any], signal: str, seconds: float) -> dict[str, Any]:
    from modd.subbroker.planning import config_for

    plan = _plan(sub)
    doc = plan.to_json()
    config = config_for(plan, 1, 3600)  # no STATUS within the run
    value = slow if signal == "slow" else flapping
    b, base, stop, loader = start_steady(tmp, config, seconds, 3600, value=value)
    capture = shutil.which("tshark") is not None and os.geteuid() == 0
    cap = Capture(tmp, b.link_port, seconds) if capture else None
    time.sleep(seconds)
    wire = wire_figures(cap.wait()) if cap else "skipped: tshark missing or no capture rights"
    stop.set()
    loader.join()
    base.close()
    b.stop()
    (stream,) = [s for s in doc["streams"] if s["sent"]]
    return {
        "signal": signal,
        "aggregation": stream["aggregation"],
        "wire": wire,
        "planner_drone_to_base_bytes_per_s": round(plan.link.drone_to_base, 1),
        "planner_value_bytes_per_s_at_most": stream.get("bytes_per_s_at_most"),
        "events_at_most": stream.get("events_at_most"),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawTextHelpFormatter)
    ap.add_argument("--seconds", type=float, default=30.0)
    ap.add_argument("--json", type=Path, default=REPO / "build" / "bench" / "events.json")
    args = ap.parse_args()
    results = []
    print(f"== One subscription at 1 s on a 25 Hz temperature, {args.seconds:.0f} s each")
    with tempfile.TemporaryDirectory() as d:
        for i, (name, sub, signal) in enumerate(CASES):
            (Path(d) / str(i)).mkdir()
            r = run(Path(d) / str(i), sub, signal, args.seconds)
            r["case"] = name
            results.append(r)
            w = r["wire"]
            measured = w["drone_to_base"]["bytes_per_s"] if isinstance(w, dict) else None
            bound = r["planner_drone_to_base_bytes_per_s"]
            within = "" if measured is None else f" ({'within' if measured <= bound else 'ABOVE'})"
            print(
                f"  {name:38s} drone->base {measured if measured is not None else w} B/s"
                f" | planner at most {bound} B/s{within}"
                + (
                    f" | value at most {r['planner_value_bytes_per_s_at_most']} B/s,"
                    f" {r['events_at_most']} events a window"
                    if r["events_at_most"] is not None
                    else ""
                )
            )
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps({"events": results}, indent=1))
    print(f"figures written to {args.json}")


if __name__ == "__main__":
    main()
