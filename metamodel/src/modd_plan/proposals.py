"""The nearest plans that fit the radio's duty cycle, when a plan does not:
a longer accepted delay (more slots per packet, fewer headers and preambles),
longer subscription periods (fewer values) and, when the model declares
resolutions, coarser ones (x 4, x 16: fewer bytes a value), each candidate planned again
by the same planner and kept only if its own report fits and it meets the
delay cap wherever the plan did; then the Pareto front of (largest delay,
energy per hour, bytes/s), lowest delay first.

Longer periods are a floor: every subscription faster than P gets period P
(the fastest, costliest ones change; the slow ones stay, and the spread of a
topic's periods, which the 3 x PING cap bounds, shrinks). The floors are the
model's own subscription periods, then the longest x 2, x 4 ... For each
floor the smallest accepted delay of a ladder that fits is found by
bisection (air time falls as the delay grows), so a refusal costs a few
dozen plans (~1.5 ms each for the paper's scenarios).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from copy import deepcopy
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from modd_contracts.types_gen import PlanProposal
from modd_model.numbers import fraction_to_decimal, to_fraction

from .radio import RadioReport

#: multipliers of the accepted delay tried (the model's delay x k)
DELAY_STEPS = (1, 2, 4, 8, 16, 32, 64, 128)
#: multipliers of the longest subscription period tried as floors
FLOOR_STEPS = (2, 4, 8, 16, 32)
#: factors the declared resolutions are coarsened by (when the model declares any)
COARSER = (4, 16)
#: proposals returned at most
MAX_PROPOSALS = 5

#: plans a model and reports its radio (None when it cannot be planned)
Planner = Callable[[Mapping[str, Any]], "tuple[RadioReport, float] | None"]


@dataclass(frozen=True)
class Proposal:
    """A changed model that fits, with its report and largest delay (s)."""

    accepted_delay_s: Fraction
    min_period_s: Fraction | None  # the floor of every subscription's period, None: unchanged
    max_delay_s: float
    report: RadioReport
    model: dict[str, Any]
    coarser: int | None = None  # the declared resolutions x this, None: unchanged

    def to_json(self) -> PlanProposal:
        r = self.report
        out: PlanProposal = {
            "accepted_delay_s": float(self.accepted_delay_s),
            "min_period_s": float(self.min_period_s) if self.min_period_s else None,
            "max_delay_s": round(self.max_delay_s, 6),
            "bytes_per_s": round(r.bytes_per_s, 3),
            "air_time_s_per_hour": round(r.air_s_per_hour, 3),
            "duty_share": round(r.duty_share or 0.0, 6),
            "energy_j_per_hour": round(r.energy_j_per_hour, 3),
            "change": self.describe(),
            "figures": r.figures,
            "air_time_bound_s_per_hour": r.air_bound_s_per_hour,
        }
        if r.calibration is not None:  # absent otherwise: uncalibrated JSON unchanged
            out["calibrated_from"] = r.calibration.source
        return out

    def describe(self) -> str:
        parts = [f"accepted delay {fraction_to_decimal(self.accepted_delay_s)} s"]
        if self.min_period_s is not None:
            floor = fraction_to_decimal(self.min_period_s)
            parts.append(f"every subscription's period at least {floor} s")
        if self.coarser is not None:
            parts.append(f"every declared resolution {self.coarser} x coarser")
        return ", ".join(parts)


def changed(
    model: Mapping[str, Any], delay: Fraction, floor: Fraction | None, coarser: int | None = None
) -> dict[str, Any]:
    """``model`` with this accepted delay, every subscription period shorter
    than ``floor`` raised to it, and every declared resolution x ``coarser``."""
    out = deepcopy(dict(model))
    out.setdefault("link", {})["acceptedDelayS"] = fraction_to_decimal(delay)
    if floor is not None:
        for sub in out.get("subscribers", []):
            if to_fraction(sub["periodS"]) < floor:
                sub["periodS"] = fraction_to_decimal(floor)
    if coarser is not None:
        for item in [*_variables(out), *out.get("subscribers", [])]:
            if "resolution" in item:
                item["resolution"] = item["resolution"] * coarser
    return out


def _variables(model: Mapping[str, Any]) -> list[dict[str, Any]]:
    return [v for s in model.get("drone", {}).get("sensors", []) for v in s["variables"]]


def coarsenings(model: Mapping[str, Any]) -> list[int | None]:
    """None (resolutions unchanged), then :data:`COARSER` if any is declared."""
    declared = any("resolution" in x for x in [*_variables(model), *model.get("subscribers", [])])
    return [None, *COARSER] if declared else [None]


def floors(model: Mapping[str, Any]) -> list[Fraction | None]:
    """None (periods unchanged), the model's subscription periods above the
    shortest, then the longest x :data:`FLOOR_STEPS`."""
    periods = sorted({to_fraction(s["periodS"]) for s in model.get("subscribers", [])})
    if not periods:
        return [None]
    return [None, *periods[1:], *(periods[-1] * k for k in FLOOR_STEPS)]


def propose(model: Mapping[str, Any], plan: Planner) -> list[Proposal]:
    """The Pareto front of the fitting candidates (at most
    :data:`MAX_PROPOSALS`), lowest delay first; empty when none fits."""
    base = to_fraction(model.get("link", {}).get("acceptedDelayS", "1"))
    ladder = [base * k for k in DELAY_STEPS]
    found: list[Proposal] = []
    for coarser in coarsenings(model):
        for floor in floors(model):
            hit = _smallest_fitting(model, ladder, floor, plan, coarser)
            if hit is not None:
                found.append(hit)
                if hit.accepted_delay_s == base:
                    break  # longer periods would only cost freshness
    return _pareto(_gaining(found))[:MAX_PROPOSALS]


def _gaining(found: list[Proposal]) -> list[Proposal]:
    """Without the coarser resolutions that gain nothing over the same plan at
    finer ones (``found`` is in coarsening order; a value's delta often fits one
    byte either way)."""
    seen: set[tuple[Fraction, Fraction | None, float]] = set()
    out = []
    for p in found:
        key = (p.accepted_delay_s, p.min_period_s, p.report.bytes_per_s)
        if key not in seen:
            seen.add(key)
            out.append(p)
    return out


def _try(
    model: Mapping[str, Any],
    delay: Fraction,
    floor: Fraction | None,
    plan: Planner,
    coarser: int | None = None,
) -> Proposal | None:
    candidate = changed(model, delay, floor, coarser)
    result = plan(candidate)
    if result is None or not result[0].fits:
        return None
    return Proposal(delay, floor, result[1], result[0], candidate, coarser)


def _smallest_fitting(
    model: Mapping[str, Any],
    ladder: list[Fraction],
    floor: Fraction | None,
    plan: Planner,
    coarser: int | None = None,
) -> Proposal | None:
    best = _try(model, ladder[-1], floor, plan, coarser)
    if best is None:
        return None
    lo, hi = 0, len(ladder) - 1  # ladder[hi] fits
    while lo < hi:
        mid = (lo + hi) // 2
        hit = _try(model, ladder[mid], floor, plan, coarser)
        if hit is None:
            lo = mid + 1
        else:
            best, hi = hit, mid
    return best


def _pareto(found: list[Proposal]) -> list[Proposal]:
    def key(p: Proposal) -> tuple[float, float, float]:
        return (p.max_delay_s, p.report.energy_j_per_hour, p.report.bytes_per_s)

    front = [
        p
        for p in found
        if not any(
            all(a <= b for a, b in zip(key(q), key(p), strict=True)) and key(q) != key(p)
            for q in found
        )
    ]
    return sorted(front, key=key)
