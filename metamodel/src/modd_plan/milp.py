"""Buffer sizes with the paper's MILP in cvxpy, solved by HiGHS.

The reference formulation (see :mod:`modd_plan.buffers` for the model and the
tie-break), vectorised: a sparse subscription x topic matrix maps buffer sizes
to n_t(j) * pm_t(j), so building the problem costs the same at 10,000
subscriptions as at 10. The tie-break is solved lexicographically, each stage
keeping the previous optima (within a quarter of a microsecond; the
MILP is written in milliseconds):

1. minimise alpha * sum z + beta * w                      -> V
2. minimise w                 s.t. stage 1 <= V           -> W
3. minimise sum_i m_i         s.t. w <= W, z_j <= m_t(j)  -> per-topic max
4. minimise sum_i n_i         s.t. m_i <= m_i*

cvxpy is imported on first use only (it takes ~0.6 s); the sizes it returns
are rounded and re-evaluated exactly.
"""

from __future__ import annotations

from fractions import Fraction
from functools import cache
from types import ModuleType
from typing import Any

import numpy as np
import scipy.sparse as sp  # type: ignore[import-untyped]

from .buffers import BufferProblem, BufferSolution, _fronts, solution_from_sizes

#: The MILP works in milliseconds: deviations are multiples of 0.001 ms, well
#: above HiGHS's feasibility tolerances (1e-7), and values stay moderate.
US_PER_UNIT = 1000
#: Slack allowed when a stage's optimum becomes the next stage's constraint:
#: a quarter of a microsecond, in MILP units.
TOLERANCE = 0.25 / US_PER_UNIT


@cache
def _cvxpy() -> ModuleType:
    import cvxpy

    return cvxpy


def _solve(cp: ModuleType, objective: Any, constraints: list[Any], n: Any) -> list[int]:
    """Solve, and return the buffer sizes rounded to the nearest integers."""
    problem = cp.Problem(cp.Minimize(objective), constraints)
    problem.solve(solver=cp.HIGHS, mip_rel_gap=0.0, mip_feasibility_tolerance=1e-9)
    if problem.status not in ("optimal", "optimal_inaccurate"):
        raise ValueError(f"HiGHS: {problem.status}")
    return [int(round(x)) for x in np.asarray(n.value, dtype=float)]


def _incidence(problem: BufferProblem) -> tuple[sp.csr_matrix, np.ndarray]:
    """(A, ps): (A @ n)_j = n_t(j) * pm_t(j) and ps, in milliseconds."""
    index = {t: i for i, t in enumerate(problem.topics)}
    rows = np.arange(len(problem.subscriptions))
    cols = np.array([index[s.topic] for s in problem.subscriptions], dtype=np.int64)
    pm = np.array(problem.publication_us, dtype=float) / US_PER_UNIT
    a = sp.csr_matrix((pm[cols], (rows, cols)), shape=(len(rows), len(problem.topics)))
    ps = np.array([s.period_us for s in problem.subscriptions], dtype=float) / US_PER_UNIT
    return a, ps


def solve_milp(problem: BufferProblem, *, tie_break: bool = True) -> BufferSolution:
    """The MILP optimum with the documented tie-break, via cvxpy + HiGHS.
    ``tie_break=False`` stops after stage 1: some optimum, as HiGHS finds it.

    Each stage's optimum is re-evaluated exactly from the rounded sizes
    before it bounds the next stage, so solver tolerances cannot accumulate.
    Infeasibility under the cap is detected and explained like
    :func:`modd_plan.buffers.solve_exact` does, then solved with the cap
    lifted for the offending topics only."""
    _, infeasible = _fronts(problem)
    if infeasible:
        relaxed = solve_milp(problem.relaxed(x.topic for x in infeasible), tie_break=tie_break)
        return BufferSolution(relaxed.sizes, relaxed.deviations_us, tuple(infeasible))
    if not problem.subscriptions:
        return solution_from_sizes(problem, [1] * len(problem.topics))
    cp = _cvxpy()
    a_mat, ps = _incidence(problem)
    n = cp.Variable(len(problem.topics), integer=True)
    z = cp.Variable(len(problem.subscriptions))
    w = cp.Variable()
    base = [z >= ps - a_mat @ n, z >= a_mat @ n - ps, z <= w, n >= 1, n <= problem.max_buffer]
    subs = problem.subscriptions
    capped = [j for j, s in enumerate(subs) if problem.cap_for(s.topic) is not None]
    if problem.cap_us is not None and capped:
        bound = z if len(capped) == len(subs) else z[np.array(capped)]
        base.append(bound <= problem.cap_us / US_PER_UNIT)
    alpha, beta = float(problem.alpha), float(problem.beta)
    stage1 = alpha * cp.sum(z) + beta * w
    sizes = _solve(cp, stage1, base, n)
    if tie_break:
        sizes = _tie_break(cp, problem, base, (n, z, w), stage1, sizes)
    return solution_from_sizes(problem, sizes)


def _ms(us: float) -> float:
    return us / US_PER_UNIT


def _tie_break(
    cp: ModuleType,
    problem: BufferProblem,
    base: list[Any],
    nzw: tuple[Any, Any, Any],
    stage1: Any,
    sizes: list[int],
) -> list[int]:
    """Stages 2-4, each bounded by the exact value of the previous stage's sizes."""
    n, z, w = nzw
    best = solution_from_sizes(problem, sizes)
    scale = min((x for x in (problem.alpha, problem.beta) if x > 0), default=Fraction(1))
    v = float(best.objective(problem.alpha, problem.beta)) * US_PER_UNIT
    base.append(stage1 <= v + TOLERANCE * float(scale))
    best = solution_from_sizes(problem, _solve(cp, w, base, n))  # stage 2
    base.append(w <= _ms(best.max_deviation_us) + TOLERANCE)
    if problem.alpha > 0:  # keep each topic's sum of deviations at its optimum
        base.append(cp.sum(z) <= _ms(sum(best.deviations_us.values())) + TOLERANCE)
    m = cp.Variable(len(problem.topics))
    incidence = (_incidence(problem)[0] != 0).astype(float)
    base += [z <= incidence @ m, m >= 0]
    best = solution_from_sizes(problem, _solve(cp, cp.sum(m), base, n))  # stage 3
    own_max = [
        max((best.deviations_us[s.name] for s in subs), default=0)
        for subs in problem.periods_by_topic()
    ]
    base.append(m <= np.array([_ms(x) for x in own_max]) + TOLERANCE)
    return _solve(cp, cp.sum(n), base, n)  # stage 4
