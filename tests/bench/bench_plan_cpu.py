"""CPU time of the planner (``make_plan`` + ``to_json``) and of the validator
on 5,000 topics x 25,000 subscriptions, median of ``--runs`` runs in one
process (issue 18: plan <= 1 s). To compare with other sources, point
``PYTHONPATH`` at their ``metamodel/src`` (it prints which planner it ran).

    .venv/bin/python tests/bench/bench_plan_cpu.py [--runs 3]
"""

from __future__ import annotations

import argparse
import importlib
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_backend_plan import valid_synthetic  # noqa: E402
from bench_planner import synthetic  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args(argv)
    plan_module = importlib.import_module("modd_plan.plan")
    validate = importlib.import_module("modd_model.validate").validate
    print("planner from", plan_module.__file__)
    model, valid = synthetic(5000, 25000), valid_synthetic(5000, 25000)
    validate(synthetic(10, 10))  # the validators' set-up, not the model's time
    plans, checks = [], []
    for _ in range(args.runs):
        start = time.process_time()
        plan_module.make_plan(model).to_json()
        plans.append(time.process_time() - start)
        start = time.process_time()
        validate(valid)
        checks.append(time.process_time() - start)
    print(f"make_plan + to_json, 5,000 x 25,000: CPU median {statistics.median(plans):.2f} s "
          f"(runs {', '.join(f'{x:.2f}' for x in plans)}); target <= 1 s")
    print(f"validate, 5,000 x 25,000 (valid): CPU median {statistics.median(checks):.2f} s "
          f"(runs {', '.join(f'{x:.2f}' for x in checks)})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
