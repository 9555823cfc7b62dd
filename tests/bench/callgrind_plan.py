"""The script whose instructions callgrind counts for the planner (issue 18):
imports, the 5,000 x 25,000 model, a small warm-up plan, then
``make_plan(model).to_json()`` once; with ``stop``, the same without the
plan (subtract its count to get the plan's).

    valgrind --tool=callgrind .venv/bin/python tests/bench/callgrind_plan.py        # I refs: A
    valgrind --tool=callgrind .venv/bin/python tests/bench/callgrind_plan.py stop   # B; plan: A - B
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_planner import synthetic  # noqa: E402
from modd_plan.plan import make_plan  # noqa: E402

model = synthetic(5000, 25000)
make_plan(synthetic(10, 10)).to_json()
if "stop" not in sys.argv[1:]:
    make_plan(model).to_json()
