"""Double-buffer sizes (paper §III-D): the exact fast method.

The MILP of the paper, for buffer sizes n_i (topic i, publication period
pm_i) and subscriptions j (period ps_j, on topic t(j))::

    minimise   alpha * sum_j z_j + beta * w
    subject to z_j >= |ps_j - n_t(j) * pm_t(j)|,  z_j <= w,  z_j <= 3 * PING,
               1 <= n_i <= MAX_BUFFER,  n_i integer

Topics are coupled only through w. For topic i let S_i(n) be the sum and
M_i(n) the largest of its subscriptions' deviations. For a fixed w = W, each
topic independently takes min{S_i(n) : M_i(n) <= W}, a step function of W
whose steps are the Pareto front of (M_i, S_i) over n. The optimum is at a
step: sweep the union of the fronts' steps in increasing W, keeping
alpha * sum S + beta * W, and take the smallest.

Ties (the objective is often flat) are broken lexicographically: smallest
objective, then smallest w, then for each topic the smallest own maximum
deviation M_i, then the smallest n_i. :mod:`modd_plan.milp` solves the same
order with cvxpy + HiGHS; the tests check both against brute force.

All deviations are integer microseconds (periods are whole microseconds).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from math import lcm

import numpy as np
import numpy.typing as npt
from modd_model.numbers import MICROS_PER_SECOND, fraction_to_decimal

IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class Subscription:
    """One subscriber's period on one topic (µs)."""

    name: str
    topic: str
    period_us: int


@dataclass(frozen=True)
class BufferProblem:
    """The MILP's data. ``cap_us`` is 3 x PING in whole µs (None: no cap);
    it does not bind the subscriptions of the ``uncapped`` topics."""

    topics: tuple[str, ...]
    publication_us: tuple[int, ...]
    subscriptions: tuple[Subscription, ...]
    max_buffer: int
    cap_us: int | None
    alpha: Fraction
    beta: Fraction
    uncapped: frozenset[str] = frozenset()

    def relaxed(self, topics: Iterable[str]) -> BufferProblem:
        """The same problem with the cap lifted for these topics."""
        return replace(self, uncapped=self.uncapped | frozenset(topics))

    def cap_for(self, topic: str) -> int | None:
        """The cap binding the subscriptions of ``topic`` (None: none)."""
        return None if topic in self.uncapped else self.cap_us

    def periods_by_topic(self) -> list[list[Subscription]]:
        index = {t: i for i, t in enumerate(self.topics)}
        out: list[list[Subscription]] = [[] for _ in self.topics]
        for s in self.subscriptions:
            out[index[s.topic]].append(s)
        return out


@dataclass(frozen=True)
class Infeasibility:
    """A topic whose subscriptions no buffer size can serve within 3 x PING."""

    topic: str
    subscribers: tuple[str, ...]
    reason: str


@dataclass(frozen=True)
class BufferSolution:
    """Buffer size per topic and the resulting deviation per subscriber (µs).
    ``infeasible`` non-empty means the cap could not be met: the sizes are
    then the optimum with the cap lifted for those topics, which violate it."""

    sizes: dict[str, int]
    deviations_us: dict[str, int]
    infeasible: tuple[Infeasibility, ...] = ()

    @property
    def max_deviation_us(self) -> int:
        return max(self.deviations_us.values(), default=0)

    def objective(self, alpha: Fraction, beta: Fraction) -> Fraction:
        """alpha * sum z + beta * w in seconds, with w the largest deviation."""
        total = sum(self.deviations_us.values())
        return (alpha * total + beta * self.max_deviation_us) / MICROS_PER_SECOND


def solution_from_sizes(problem: BufferProblem, sizes: Sequence[int]) -> BufferSolution:
    """Evaluate given sizes exactly (the deviations are recomputed, never
    taken from a floating-point solver)."""
    pm = dict(zip(problem.topics, problem.publication_us, strict=True))
    by_name = dict(zip(problem.topics, sizes, strict=True))
    devs = {
        s.name: abs(s.period_us - by_name[s.topic] * pm[s.topic]) for s in problem.subscriptions
    }
    return BufferSolution({t: int(n) for t, n in by_name.items()}, devs)


#: Candidate buffer sizes examined per topic at most (an int64 of each of a
#: few tables each): the work and memory of a plan never depend on MAX_BUFFER.
CANDIDATE_LIMIT = 1 << 19


class BufferTooLarge(ValueError):
    """A topic whose useful buffer sizes are too many to examine."""

    def __init__(self, topic: str, subscribers: Sequence[str], count: int) -> None:
        self.topic = topic
        self.subscribers = tuple(subscribers)
        super().__init__(
            f"{topic}: {count:,} candidate buffer sizes between its shortest and longest "
            f"subscription period, over the planner's bound {CANDIDATE_LIMIT:,}; bring the "
            "subscription periods of this topic closer together or publish it less often"
        )


def candidate_range(periods_us: Sequence[int], pm_us: int, max_buffer: int) -> tuple[int, int]:
    """The buffer sizes ``lo..hi`` that can be optimal. Below ``ps_min / pm``
    every deviation shrinks as ``n`` grows, above ``ps_max / pm`` every one
    grows, so a size outside is worse on both the sum and the maximum than
    the nearest end (and no nearer the cap)."""
    if not periods_us:
        return 1, 1
    hi = min(max_buffer, -(-max(periods_us) // pm_us))
    lo = min(max(1, min(periods_us) // pm_us), hi)
    return lo, hi


def topic_table(
    periods_us: Sequence[int], pm_us: int, max_buffer: int, lo: int = 1, hi: int | None = None
) -> tuple[IntArray, IntArray]:
    """S(n) and M(n) for n = lo..hi (default 1..max_buffer; index n - lo): the
    sum and the largest of |ps_j - n * pm| over the topic's subscriptions."""
    hi = max_buffer if hi is None else hi
    x = np.arange(lo, hi + 1, dtype=np.int64) * pm_us
    if not periods_us:
        zero = np.zeros(len(x), dtype=np.int64)
        return zero, zero.copy()
    ps = np.sort(np.asarray(periods_us, dtype=np.int64))
    prefix = np.concatenate(([0], np.cumsum(ps)))
    k = np.searchsorted(ps, x, side="right")
    below = x * k - prefix[k]
    above = (prefix[-1] - prefix[k]) - x * (len(ps) - k)
    m = np.maximum(ps[-1] - x, x - ps[0])
    return below + above, m


@dataclass(frozen=True)
class _Front:
    """Pareto front of (M, S) over n: M ascending, S strictly decreasing,
    each point with the smallest n reaching it."""

    m: IntArray
    s: IntArray
    n: IntArray


def _front(s: IntArray, m: IntArray, allowed: npt.NDArray[np.bool_], lo: int) -> _Front:
    n = np.flatnonzero(allowed).astype(np.int64) + lo
    s, m = s[allowed], m[allowed]
    order = np.lexsort((n, s, m))
    s, m, n = s[order], m[order], n[order]
    running = np.minimum.accumulate(s)
    keep = np.concatenate(([True], s[1:] < running[:-1]))
    return _Front(m[keep], s[keep], n[keep])


def _explain(
    topic: str, subs: Sequence[Subscription], pm_us: int, m: IntArray, cap_us: int, first_n: int
) -> str:
    def sec(us: int | Fraction) -> str:
        return fraction_to_decimal(Fraction(us) / MICROS_PER_SECOND) + " s"

    lo = min(subs, key=lambda s: s.period_us)
    hi = max(subs, key=lambda s: s.period_us)
    cap = sec(cap_us)
    if hi.period_us - lo.period_us > 2 * cap_us:
        return (
            f"subscription periods range from {sec(lo.period_us)} ({lo.name}) to "
            f"{sec(hi.period_us)} ({hi.name}): whatever the buffer size, one of them waits at "
            f"least {sec(Fraction(hi.period_us - lo.period_us, 2))} more or less than its period, "
            f"over the limit 3 x PING = {cap}"
        )
    i = int(np.argmin(m))
    best = i + first_n - 1
    return (
        f"with a publication period of {sec(pm_us)} the best buffer size n = {best + 1} "
        f"(n x pm = {sec((best + 1) * pm_us)}) still leaves a deviation of {sec(int(m[i]))}, "
        f"over the limit 3 x PING = {cap}"
    )


def _fronts(problem: BufferProblem) -> tuple[list[_Front | None], list[Infeasibility]]:
    """Per topic its front (None for a topic nobody subscribes to) and the
    topics the cap makes infeasible."""
    fronts: list[_Front | None] = []
    infeasible: list[Infeasibility] = []
    for topic, pm_us, subs in zip(
        problem.topics, problem.publication_us, problem.periods_by_topic(), strict=True
    ):
        if not subs:
            fronts.append(None)
            continue
        periods = [x.period_us for x in subs]
        lo, hi = candidate_range(periods, pm_us, problem.max_buffer)
        if hi - lo + 1 > CANDIDATE_LIMIT:
            raise BufferTooLarge(topic, [x.name for x in subs], hi - lo + 1)
        s, m = topic_table(periods, pm_us, problem.max_buffer, lo, hi)
        if problem.alpha == 0:
            s = np.zeros_like(s)
        cap = problem.cap_for(topic)
        allowed = np.ones(len(m), dtype=bool) if cap is None else m <= cap
        if not allowed.any():
            assert cap is not None
            reason = _explain(topic, subs, pm_us, m, cap, lo)
            infeasible.append(Infeasibility(topic, tuple(x.name for x in subs), reason))
            fronts.append(None)
            continue
        fronts.append(_front(s, m, allowed, lo))
    return fronts, infeasible


def _best_w(fronts: Sequence[_Front], a: int, b: int) -> int:
    """The smallest w minimising a * sum_i min{S_i : M_i <= w} + b * w."""
    w0 = max(int(f.m[0]) for f in fronts)
    f0 = sum(int(f.s[np.searchsorted(f.m, w0, side="right") - 1]) for f in fronts)
    ms = [f.m[1:][f.m[1:] > w0] for f in fronts]
    ds = [np.diff(f.s)[f.m[1:] > w0] for f in fronts]
    ev_m = np.concatenate([np.zeros(0, dtype=np.int64), *ms])
    if len(ev_m) == 0:
        return w0
    order = np.argsort(ev_m, kind="stable")
    ev_m = ev_m[order]
    ev_f = f0 + np.cumsum(np.concatenate(ds)[order])
    last = np.concatenate((ev_m[1:] != ev_m[:-1], [True]))  # last event at each w
    cand_w, cand_f = ev_m[last], ev_f[last]
    objective = [a * int(f) + b * int(w) for f, w in zip(cand_f, cand_w, strict=True)]
    i = int(np.argmin(objective))
    return int(cand_w[i]) if objective[i] < a * f0 + b * w0 else w0


def solve_exact(problem: BufferProblem) -> BufferSolution:
    """The MILP's optimum with the documented tie-break, exactly.

    When the cap makes it infeasible, returns the optimum with the cap lifted
    for the offending topics only, ``infeasible`` naming them."""
    fronts, infeasible = _fronts(problem)
    if infeasible:
        relaxed = solve_exact(problem.relaxed(x.topic for x in infeasible))
        return BufferSolution(relaxed.sizes, relaxed.deviations_us, tuple(infeasible))
    d = lcm(problem.alpha.denominator, problem.beta.denominator)
    a, b = int(problem.alpha * d), int(problem.beta * d)
    used = [f for f in fronts if f is not None]
    w = _best_w(used, a, b) if used else 0
    sizes = [
        1 if f is None else int(f.n[np.searchsorted(f.m, w, side="right") - 1]) for f in fronts
    ]
    return solution_from_sizes(problem, sizes)
