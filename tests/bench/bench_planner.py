"""Planner benchmark: planning time (solver included) for the paper's
scenarios, the 26-day hyperperiod example, 200 topics x 1000 subscriptions
and 2000 topics x 10000 subscriptions, with the exact method and with the
cvxpy MILP; then the worst cases of issue 18, each in a fresh process (CPU
time and peak memory): adversarial sets of e non-dividing sent periods
(e = 16 ... 40), models with periods on a 0.1 s grid, 5,000 topics x 25,000
subscriptions, maxBuffer 1e8, and the CPU cost of ``modd --help`` and
``modd plan scenario1.modd``. Prints figures; asserts nothing about time.

    .venv/bin/python tests/bench/bench_planner.py [--quick] [--worst-only]

Targets (issue 3): < 0.2 s for 200 x 1000, < 2 s for 2000 x 10000.
Targets (issue 18): 24 non-dividing periods <= 0.1 s and <= 100 MB; 100 x 500
on a 0.1 s grid <= 0.2 s; 5,000 x 25,000 <= 1 s; `modd plan` <= 0.3 s CPU.
"""

from __future__ import annotations

import argparse
import json
import random
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from modd_model import ModelError, load_model
from modd_model.query import topics
from modd_plan.milp import solve_milp
from modd_plan.plan import buffer_problem, constants_for, make_plan

REPO = Path(__file__).resolve().parents[2]
SCENARIOS = REPO / "metamodel" / "examples" / "scenarios"
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
            {
                "name": f"p{i}",
                "periodS": rng.choice(PUB_PERIODS),
                "topics": topics[10 * i : 10 * i + 10],
            }
            for i in range(n_topics // 10)
        ],
        "subscribers": [
            {
                "name": f"sub{k}",
                "topic": rng.choice(topics),
                "periodS": rng.choice(SUB_PERIODS),
                "aggregation": rng.choice(AGGS),
            }
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


PRIMES = [p for p in range(2, 600) if all(p % q for q in range(2, int(p**0.5) + 1))]


def period_set(kind: str, e: int) -> list[str]:
    """e sent periods (s) of which none divides another: pairwise coprime
    (primes x 10 ms, primes x 0.1 s), consecutive integers (x 1 ms, many
    shared factors) or a cycle of prime pairs (x 1 ms: one connected group,
    the lattice's worst case)."""
    if kind == "primes":
        return [f"{p / 100:.2f}" for p in PRIMES[1 : e + 1]]
    if kind == "grid":
        return [f"{p / 10:.1f}" for p in PRIMES[1 : e + 1]]
    if kind == "consecutive":
        return [f"{k / 1000:.3f}" for k in range(e, 2 * e)]
    return [f"{PRIMES[i] * PRIMES[(i + 1) % e] / 1000:.3f}" for i in range(e)]


def periods_model(periods: list[str], pub: str) -> dict[str, Any]:
    """One MAX subscriber per period, each on its own topic."""
    model = synthetic(10 * (len(periods) // 10 + 1), 0)
    for p in model["publishers"]:
        p["periodS"] = pub
    model["subscribers"] = [
        {"name": f"sub{k}", "topic": f"d.s{k // 10}.v{k % 10}", "periodS": p, "aggregation": "MAX"}
        for k, p in enumerate(periods)
    ]
    return model


def grid_model(n_topics: int, n_subs: int, seed: int = 1) -> dict[str, Any]:
    """Subscriber periods drawn from primes x 0.1 s (0.3, 0.5, 0.7, 1.1, 1.3, ...,
    11.3 s), publication every 0.1 s."""
    rng = random.Random(seed)
    model = synthetic(n_topics, 0, seed)
    for p in model["publishers"]:
        p["periodS"] = "0.1"
    tops = [t for p in model["publishers"] for t in p["topics"]]
    grid = [f"{p / 10:.1f}" for p in PRIMES[1:30]]
    model["subscribers"] = [
        {
            "name": f"sub{k}",
            "topic": rng.choice(tops),
            "periodS": grid[k % len(grid)],
            "aggregation": rng.choice(["MIN", "MAX", "AVERAGE"]),
        }
        for k in range(n_subs)
    ]
    return model


def worst_case(name: str) -> dict[str, Any]:
    """One worst case, planned in this process: CPU s, peak MB, outcome."""
    if name.startswith("e:"):
        _, kind, e = name.split(":")
        pub = "0.001" if kind in ("consecutive", "cycle") else "0.01"
        model = periods_model(period_set(kind, int(e)), pub)
    elif name.startswith("grid:"):
        _, t, n = name.split(":")
        model = grid_model(int(t), int(n))
    elif name.startswith("synthetic:"):
        _, t, n = name.split(":")
        model = synthetic(int(t), int(n))
    elif name.startswith("validate:"):  # the validator alone, on a valid model
        import importlib

        from bench_backend_plan import valid_synthetic

        _, t, n = name.split(":")
        model = valid_synthetic(int(t), int(n))
        validate = importlib.import_module("modd_model.validate").validate
        start = time.process_time()
        errors = [d for d in validate(model) if d.severity == "error"]
        cpu = time.process_time() - start
        rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
        return {"cpu_s": cpu, "peak_mb": rss, "outcome": f"{len(errors)} errors (validation)"}
    else:  # maxbuffer
        model = load_model(SCENARIOS / "scenario1.modd")
    start = time.process_time()
    try:
        plan = make_plan(model, max_buffer=10**8 if name == "maxbuffer" else None).to_json()
        outcome = (
            f"{plan['messages_per_hyperperiod']:.3g} messages"
            if plan["messages_per_hyperperiod"] > 10**6
            else f"{plan['messages_per_hyperperiod']} messages"
        )
    except ModelError as exc:
        outcome = f"located error ({len(exc.diagnostics)} subscriptions)"
    except ValueError as exc:  # e.g. a hyperperiod past the decimal strings' range
        outcome = f"ValueError: {str(exc)[:48]}"
    cpu = time.process_time() - start
    rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    return {"cpu_s": cpu, "peak_mb": rss, "outcome": outcome}


def cli_cpu(*argv: str) -> float:
    """CPU seconds (user + system) of ``modd ARGV``, median of 3."""
    exe = Path(sys.executable).with_name("modd")
    times = []
    for _ in range(3):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        subprocess.run([str(exe), *argv], check=True, capture_output=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        times.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
    return statistics.median(times)


def worst_cases(quick: bool) -> None:
    names = [
        f"e:{kind}:{e}"
        for kind in ("primes", "grid", "consecutive", "cycle")
        for e in ((16, 24, 40) if quick else (16, 20, 24, 32, 40))
    ]
    names += [
        "grid:10:25",
        "grid:100:500",
        "synthetic:5000:25000",
        "validate:5000:25000",
        "maxbuffer",
    ]
    print("\nworst cases (issue 18), each in a fresh process; e = non-dividing sent periods")
    print(f"{'case':34} {'CPU':>9} {'peak RSS':>9}  outcome")
    for name in names:
        out = subprocess.run(
            [sys.executable, __file__, "--case", name], check=True, capture_output=True, text=True
        ).stdout
        r = json.loads(out.strip().splitlines()[-1])
        print(f"{name:34} {r['cpu_s'] * 1e3:7.1f} ms {r['peak_mb']:6.0f} MB  {r['outcome']}")
    print(f"{'modd --help':34} {cli_cpu('--help') * 1e3:7.1f} ms CPU")
    print(
        f"{'modd plan scenario1.modd':34} "
        f"{cli_cpu('plan', str(SCENARIOS / 'scenario1.modd')) * 1e3:7.1f} ms CPU"
    )


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
    ap.add_argument(
        "--all",
        action="store_true",
        help="also plan 2000 x 10000 with the cvxpy tie-break (minutes)",
    )
    ap.add_argument("--worst-only", action="store_true", help="only the issue 18 worst cases")
    ap.add_argument("--case", help=argparse.SUPPRESS)  # one worst case, JSON out
    args = ap.parse_args(argv)
    if args.case:
        print(json.dumps(worst_case(args.case)))
        return 0
    if args.worst_only:
        worst_cases(args.quick)
        return 0
    cases: list[tuple[str, dict[str, Any]]] = [
        ("scenario 1 (3 topics x 7 subs)", load_model(SCENARIOS / "scenario1.modd")),
        ("scenario 2 (19 topics x 19 subs)", load_model(SCENARIOS / "scenario2.modd")),
        ("26-day hyperperiod (7 periods)", twenty_six_days()),
        ("200 topics x 1000 subs", synthetic(200, 1000)),
        ("2000 topics x 10000 subs", synthetic(2000, 10000)),
    ]
    make_plan(cases[0][1], method="cvxpy")  # import cvxpy once, outside the timings
    print(
        f"{'case':34} {'plan, exact':>12} {'plan, cvxpy':>12} {'paper MILP':>11}  "
        "hyperperiod, messages   (median of runs)"
    )
    for name, model in cases:
        repeat = 3 if args.quick else 7
        exact = timed(lambda m=model: make_plan(m), repeat)  # type: ignore[misc]
        big = len(model["subscribers"]) > 5000

        def by_milp(m: Any = model) -> Any:
            return make_plan(m, method="cvxpy")

        milp = None if big and not args.all else timed(by_milp, 1 if big else repeat)
        plan = make_plan(model).to_json()
        stage1 = timed(lambda m=model: paper_milp(m), 1 if big else repeat)  # type: ignore[misc]
        milp_s = f"{milp[0] * 1e3:9.1f} ms" if milp else "skipped"
        print(
            f"{name:34} {exact[0] * 1e3:9.1f} ms {milp_s:>12} {stage1[0] * 1e3:8.1f} ms  "
            f"{plan['hyperperiod_s']} s, {plan['messages_per_hyperperiod']}"
        )
    worst_cases(args.quick)
    return 0


if __name__ == "__main__":
    sys.exit(main())
