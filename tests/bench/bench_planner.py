"""Planner benchmark: planning time (solver included) for the paper's
scenarios, the 26-day hyperperiod example, 200 topics x 1000 subscriptions
and 2000 topics x 10000 subscriptions, with the exact method and with the
cvxpy MILP. Prints figures; asserts nothing about time.

    .venv/bin/python tests/bench/bench_planner.py [--quick]

Targets (issue 3): < 0.2 s for 200 x 1000, < 2 s for 2000 x 10000.
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from modd_model import load_model
from modd_model.query import topics
from modd_plan.milp import solve_milp
from modd_plan.plan import buffer_problem, constants_for, make_plan

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO.parent / "shared" / "scenarios"
PUB_PERIODS = ["0.01", "0.02", "0.04", "0.05", "0.1", "0.2", "0.5", "1.0"]
SUB_PERIODS = ["0.25", "0.5", "1.0", "2.0", "2.5", "5.0", "10.0", "0.3", "0.7", "1.5"]
AGGS = ["MIN", "MAX", "AVERAGE", "FIRST", "LAST", "COUNT", "SUM"]


def synthetic(n_topics: int, n_subs: int, seed: int = 1) -> dict[str, Any]:
    """A valid model: topics spread over sensors of 10 variables, one
    publisher per sensor, random subscriptions."""
    rng = random.Random(seed)
    sensors = [
        {"name": f"s{i}", "variables": [{"name": f"v{j}", "unit": "NONE"} for j in range(10)]}
        for i in range(n_topics // 10)
    ]
    topics = [f"d.s{i}.v{j}" for i in range(n_topics // 10) for j in range(10)]
    return {
        "schemaVersion": "1.0",
        "drone": {"name": "d", "sensors": sensors},
        "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 7171}, "logPath": "/tmp/l"},
        "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 7272}, "configPath": "/tmp/c"},
        "publishers": [
            {"name": f"p{i}", "periodS": rng.choice(PUB_PERIODS),
             "topics": topics[10 * i : 10 * i + 10]}
            for i in range(n_topics // 10)
        ],
        "subscribers": [
            {"name": f"sub{k}", "topic": rng.choice(topics),
             "periodS": rng.choice(SUB_PERIODS), "aggregation": rng.choice(AGGS)}
            for k in range(n_subs)
        ],
    }


def twenty_six_days() -> dict[str, Any]:
    periods = ["0.3", "0.7", "1.1", "2.3", "1.3", "1.7", "1.9"]
    model = synthetic(10, 0)
    model["subscribers"] = [
        {"name": f"sub{k}", "topic": f"d.s0.v{k}", "periodS": p, "aggregation": "MAX"}
        for k, p in enumerate(periods)
    ]
    return model


def paper_milp(model: dict[str, Any]) -> None:
    """The paper's MILP alone (stage 1, no tie-break), cvxpy + HiGHS."""
    problem, _ = buffer_problem(model, topics(model), constants_for(model))
    solve_milp(problem, tie_break=False)


def timed(fn: Callable[[], object], repeat: int) -> tuple[float, float]:
    """(median, min) wall time in seconds."""
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), min(times)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--quick", action="store_true", help="fewer repetitions")
    ap.add_argument("--all", action="store_true",
                    help="also plan 2000 x 10000 with the cvxpy tie-break (minutes)")
    args = ap.parse_args(argv)
    cases: list[tuple[str, dict[str, Any]]] = [
        ("scenario 1 (3 topics x 7 subs)", load_model(SCENARIOS / "scenario1.modd")),
        ("scenario 2 (19 topics x 19 subs)", load_model(SCENARIOS / "scenario2.modd")),
        ("26-day hyperperiod (7 periods)", twenty_six_days()),
        ("200 topics x 1000 subs", synthetic(200, 1000)),
        ("2000 topics x 10000 subs", synthetic(2000, 10000)),
    ]
    make_plan(cases[0][1], method="cvxpy")  # import cvxpy once, outside the timings
    print(f"{'case':34} {'plan, exact':>12} {'plan, cvxpy':>12} {'paper MILP':>11}  "
          "hyperperiod, messages   (median of runs)")
    for name, model in cases:
        repeat = 3 if args.quick else 7
        exact = timed(lambda m=model: make_plan(m), repeat)  # type: ignore[misc]
        big = len(model["subscribers"]) > 5000
        milp = None if big and not args.all else timed(
            lambda m=model: make_plan(m, method="cvxpy"), 1 if big else repeat  # type: ignore[misc]
        )
        plan = make_plan(model).to_json()
        stage1 = timed(lambda m=model: paper_milp(m), 1 if big else repeat)  # type: ignore[misc]
        milp_s = f"{milp[0] * 1e3:9.1f} ms" if milp else "skipped"
        print(f"{name:34} {exact[0] * 1e3:9.1f} ms {milp_s:>12} {stage1[0] * 1e3:8.1f} ms  "
              f"{plan['hyperperiod_s']} s, {plan['messages_per_hyperperiod']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
