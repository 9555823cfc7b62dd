"""One digest of the whole plan JSON (sorted keys) per model, for comparing
two planners: run it on each source tree and diff the outputs. Models: 40
random ones with every aggregation and extra periods (many streams per
topic: derivations, helper ALL streams), 6 synthetic ones, the prime grid,
the 26-day hyperperiod, the two scenarios; ``--big`` adds 2,000 x 10,000 and
5,000 x 25,000.

    .venv/bin/python tests/bench/plan_digests.py --big > after.txt
    PYTHONPATH=<old>/metamodel/src .venv/bin/python tests/bench/plan_digests.py --big > before.txt
    diff before.txt after.txt

(``PYTHONPATH`` may point at a directory holding only the old ``modd_plan``.)
"""

from __future__ import annotations

import argparse
import hashlib
import json
import random
import sys
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_planner import grid_model, synthetic, twenty_six_days  # noqa: E402
from modd_model.io import load_model  # noqa: E402
from modd_plan.plan import make_plan  # noqa: E402
from modd_plan.streams import AGGREGATIONS  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
EXTRA_PERIODS = ["0.1", "0.2", "0.4", "0.6", "3.0", "4.0", "20.0", "0.05"]


def random_model(seed: int, n_topics: int, n_subs: int) -> dict[str, Any]:
    model = synthetic(n_topics, n_subs, seed)
    rng = random.Random(seed * 7 + 1)
    for sub in model["subscribers"]:
        sub["aggregation"] = rng.choice(AGGREGATIONS)
        if rng.random() < 0.3:
            sub["periodS"] = rng.choice(EXTRA_PERIODS)
    return model


def models(big: bool) -> list[tuple[str, dict[str, Any]]]:
    out = [
        (f"rnd{seed}", random_model(seed, 10 * (1 + seed % 5), 30 + 20 * seed))
        for seed in range(40)
    ]
    out += [(f"syn{seed}", synthetic(100 + 50 * seed, 500 + 300 * seed, seed)) for seed in range(6)]
    out += [("grid", grid_model(100, 1000)), ("26d", twenty_six_days())]
    if big:
        out += [("big", synthetic(2000, 10000)), ("huge", synthetic(5000, 25000))]
    for name in ("scenario1", "scenario2"):
        path = ROOT / "metamodel" / "examples" / "scenarios" / f"{name}.modd"
        out.append((name, load_model(path)))
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--big", action="store_true", help="add the two large models")
    args = ap.parse_args(argv)
    for name, model in models(args.big):
        try:
            text = json.dumps(make_plan(model).to_json(), sort_keys=True)
        except Exception as exc:  # a planning error is part of the result
            text = f"ERR {exc!r}"
        print(name, hashlib.sha256(text.encode()).hexdigest()[:16], len(text))
    return 0


if __name__ == "__main__":
    sys.exit(main())
