"""The event vectors (``events.json``): scripted signals (steps, a ramp, noise
around a threshold, a flapping signal, an int counter) and, for ON_CHANGE and
THRESHOLD subscriptions of them, each window's events and coalesced count by
the reference definition (modd_contracts.events, docs/planning.md "Event
subscriptions"). The C++ PubBroker's detector
(runtime/cpp/tests/test_events.cpp) is checked against them; a test checks
that this script reproduces the committed file.

Run: .venv/bin/python contracts/vectors/gen_events.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from modd_contracts.events import EventSpec, windows
from modd_contracts.link_wire_gen import Crossing, DeadbandMode, EventKind

HERE = Path(__file__).resolve().parent
OUT = HERE / "events.json"
EPOCH = 1_000_000_000  # ns: the config's epoch
PERIOD = 1_000_000_000  # ns: 1-s windows
STEP = 100_000_000  # ns: 10 Hz samples


def _signals() -> list[tuple[str, str, list[float] | list[int]]]:
    rng = np.random.default_rng(45)
    steps = [4.0] * 12 + [6.0] * 12 + [5.9] * 6 + [3.0] * 10
    ramp = [float(x) for x in np.round(np.linspace(0.0, 10.0, 41), 6)]
    noise = [float(x) for x in np.round(5.0 + rng.normal(0.0, 0.3, 60), 6)]
    flapping = [4.0 if k % 2 else 6.0 for k in range(50)]
    counter = [int(x) for x in np.cumsum(rng.integers(0, 3, 40))]
    return [
        ("steps", "float64", steps),
        ("ramp", "float32", [float(np.float32(x)) for x in ramp]),
        ("noise around 5", "float64", noise),
        ("flapping", "float64", flapping),
        ("int counter", "int", counter),
    ]


def _specs() -> list[tuple[str, EventSpec]]:
    on, th = EventKind.ON_CHANGE, EventKind.THRESHOLD
    return [
        ("on change 0.5", EventSpec(on, 20, deadband=0.5)),
        ("on change 0", EventSpec(on, 20)),
        ("on change 5 %", EventSpec(on, 20, deadband=0.05, mode=DeadbandMode.RELATIVE)),
        ("on change, 2 a window", EventSpec(on, 2, deadband=0.1)),
        ("threshold 5 both", EventSpec(th, 20, level=5.0)),
        (
            "threshold 5 up h 0.5",
            EventSpec(th, 20, level=5.0, hysteresis=0.5, crossing=Crossing.UP),
        ),
        (
            "threshold 5 down h 0.2",
            EventSpec(th, 20, level=5.0, hysteresis=0.2, crossing=Crossing.DOWN),
        ),
        ("threshold 5 both, 1 a window", EventSpec(th, 1, level=5.0)),
    ]


def _spec_json(s: EventSpec) -> dict[str, Any]:
    return {
        "kind": int(s.kind),
        "maxEvents": s.max_events,
        "deadband": s.deadband,
        "mode": int(s.mode),
        "level": s.level,
        "hysteresis": s.hysteresis,
        "crossing": int(s.crossing),
    }


def vectors() -> dict[str, Any]:
    cases = []
    for name, vtype, values in _signals():
        samples = [(EPOCH + k * STEP + 7_000, x) for k, x in enumerate(values)]
        for spec_name, spec in _specs():
            wins = windows(spec, samples, EPOCH, PERIOD)
            cases.append(
                {
                    "name": f"{name}: {spec_name}",
                    "type": vtype,
                    "spec": _spec_json(spec),
                    "samples": [[t, x] for t, x in samples],
                    "windows": [
                        {"events": [[t, x] for t, x in w.events], "coalesced": w.coalesced}
                        for w in wins
                    ],
                }
            )
    return {
        "doc": "Scripted signals (t ns, value) and, per event subscription (codes of "
        "wire.json's events group), each window's events (t ns, value) and coalesced "
        f"count by modd_contracts.events; epoch {EPOCH} ns, period {PERIOD} ns; written "
        "by gen_events.py.",
        "epochNs": EPOCH,
        "periodNs": PERIOD,
        "vectors": cases,
    }


def text() -> str:
    """The file: one vector a line."""
    v = vectors()
    lines = ",\n  ".join(json.dumps(c) for c in v["vectors"])
    head = {k: v[k] for k in ("doc", "epochNs", "periodNs")}
    fields = ",\n ".join(f"{json.dumps(k)}: {json.dumps(x)}" for k, x in head.items())
    return f'{{\n {fields},\n "vectors": [\n  {lines}\n ]\n}}\n'


if __name__ == "__main__":
    OUT.write_text(text(), encoding="utf-8")
    print(f"wrote {OUT}")
