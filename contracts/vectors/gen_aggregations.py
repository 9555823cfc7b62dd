"""The aggregation vectors (``aggregations.json``): windows of samples and what
each exact statistic of the window is, computed by numpy (the oracle, not the
project's code): MEDIAN is ``numpy.median``, STDDEV ``numpy.std`` (ddof=0,
the population standard deviation), RANGE ``numpy.ptp``, PERCENTILE(p)
``numpy.percentile(x, p)`` (its default ``method="linear"``) for each p of
``PERCENTILES``. The C++ accumulator
(runtime/cpp/tests/test_accumulator.cpp) and the planner's ``aggregate``
(metamodel/tests/plan/test_aggregations.py) are checked against them; a test
checks that this script reproduces the committed file.

Run: .venv/bin/python contracts/vectors/gen_aggregations.py
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

HERE = Path(__file__).resolve().parent
OUT = HERE / "aggregations.json"
#: The p of the PERCENTILE vectors: in (0, 100], the tails and fractions included.
PERCENTILES = (0.1, 5, 25, 33.3, 50, 90, 95, 99, 99.9, 100)


def _windows() -> list[tuple[str, str, list[float] | list[int]]]:
    rng = np.random.default_rng(45)
    noisy = (20.0 + rng.normal(0.0, 0.5, 257)).round(6)
    noisy[[10, 100, 200]] = [95.0, -40.0, 300.0]  # spikes a median ignores
    return [
        ("one sample", "float64", [4.25]),
        ("odd count", "float64", [3.0, -1.5, 7.25, 0.5, 2.0]),
        ("even count", "float64", [3.0, -1.5, 7.25, 0.5]),
        ("repeated values", "float64", [1.0, 1.0, 1.0, 2.0]),
        ("spiky turbidity", "float64", [float(x) for x in noisy]),
        ("large offset", "float64", [1e9 + 0.1, 1e9 + 0.2, 1e9 + 0.3]),
        (
            "float32 accelerations",
            "float32",
            [float(np.float32(x)) for x in rng.normal(0.0, 9.81, 64)],
        ),
        ("int odd", "int", [5, -7, 12, 0, 3]),
        ("int even", "int", [5, -7, 12, 0]),
        ("int counts", "int", [int(x) for x in rng.integers(-1000, 1000, 100)]),
    ]


def vectors() -> dict[str, Any]:
    cases = []
    for name, vtype, samples in _windows():
        x = np.asarray(samples, dtype=np.float64)
        cases.append(
            {
                "name": name,
                "type": vtype,
                "samples": samples,
                "MEDIAN": float(np.median(x)),
                "STDDEV": float(np.std(x, ddof=0)),
                "RANGE": int(np.ptp(np.asarray(samples))) if vtype == "int" else float(np.ptp(x)),
                "PERCENTILE": {f"{p:g}": float(np.percentile(x, p)) for p in PERCENTILES},
            }
        )
    return {
        "doc": "Windows of samples and their exact MEDIAN (numpy.median), STDDEV "
        "(numpy.std, ddof=0), RANGE (numpy.ptp) and PERCENTILE(p) (numpy.percentile, "
        "method='linear', keyed by p), in double precision over the samples as "
        "float64; written by gen_aggregations.py.",
        "vectors": cases,
    }


def text() -> str:
    """The file: one vector a line."""
    v = vectors()
    lines = ",\n  ".join(json.dumps(c) for c in v["vectors"])
    return f'{{\n "doc": {json.dumps(v["doc"])},\n "vectors": [\n  {lines}\n ]\n}}\n'


if __name__ == "__main__":
    OUT.write_text(text(), encoding="utf-8")
    print(f"wrote {OUT}")
