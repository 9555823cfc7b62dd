"""The live plan: the planning engine's own output for a model, or the
diagnostics saying why there is none. Same code as the brokers run.

>>> live_plan(load_text(text, "x.modd")).plan["buffer_sizes"]   # doctest: +SKIP
{'usv.accelerometer.accel_x': 28, ...}
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Literal

from modd_model import LoadResult
from modd_model.diagnostics import Diagnostic
from modd_plan import make_plan

from .modelio import diagnostics_json

Method = Literal["exact", "cvxpy"]


@dataclass(frozen=True)
class LivePlan:
    plan: dict[str, Any] | None
    diagnostics: list[dict[str, object]]
    elapsed_ms: float

    def to_json(self) -> dict[str, Any]:
        return {
            "ok": self.plan is not None,
            "plan": self.plan,
            "diagnostics": self.diagnostics,
            "elapsed_ms": round(self.elapsed_ms, 3),
        }


def live_plan(result: LoadResult, method: Method = "exact") -> LivePlan:
    """Plan a loaded model when it has no errors; never raises for bad models."""
    start = time.perf_counter()
    diags = list(result.diagnostics)
    plan = None
    if result.model is not None and not result.errors:
        try:
            plan = make_plan(result.model, method=method).to_json()
        except (ValueError, KeyError, ArithmeticError) as exc:
            diags.append(Diagnostic(f"the planner cannot plan this model: {exc}", ""))
    return LivePlan(plan, diagnostics_json(diags), (time.perf_counter() - start) * 1000)


def preload_milp() -> None:
    """Import cvxpy once (about 0.6 s) so that no request pays for it."""
    from modd_plan import milp  # noqa: F401
