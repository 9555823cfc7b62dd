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

from bisect import bisect_right
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, replace
from fractions import Fraction
from functools import lru_cache
from math import lcm
from typing import TYPE_CHECKING

from modd_model.numbers import MICROS_PER_SECOND, fraction_to_decimal

if TYPE_CHECKING:  # numpy is imported only for models past SMALL_CANDIDATES
    import numpy as np
    import numpy.typing as npt

    IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True, init=False)
class Subscription:
    """One subscriber's period on one topic (µs)."""

    name: str
    topic: str
    period_us: int

    def __init__(self, name: str, topic: str, period_us: int) -> None:
        # one dictionary update, not a frozen dataclass's setattr per field
        # (a plan builds one per subscription)
        self.__dict__.update(name=name, topic=topic, period_us=period_us)


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
    import numpy as np

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
    import numpy as np

    n = np.flatnonzero(allowed).astype(np.int64) + lo
    s, m = s[allowed], m[allowed]
    order = np.lexsort((n, s, m))
    s, m, n = s[order], m[order], n[order]
    running = np.minimum.accumulate(s)
    keep = np.concatenate(([True], s[1:] < running[:-1]))
    return _Front(m[keep], s[keep], n[keep])


@lru_cache(maxsize=65_536)  # bounded: many infeasible topics repeat few figures
def _seconds(us: int) -> str:
    return fraction_to_decimal(Fraction(us, MICROS_PER_SECOND)) + " s"


@lru_cache(maxsize=65_536)  # bounded: many infeasible topics repeat few figures
def _half_seconds(us: int) -> str:
    return fraction_to_decimal(Fraction(us, 2 * MICROS_PER_SECOND)) + " s"


def _explain(
    topic: str,
    subs: Sequence[Subscription],
    pm_us: int,
    m: IntArray | Sequence[int],
    cap_us: int,
    first_n: int,
) -> str:
    sec = _seconds
    lo = min(subs, key=lambda s: s.period_us)
    hi = max(subs, key=lambda s: s.period_us)
    cap = sec(cap_us)
    if hi.period_us - lo.period_us > 2 * cap_us:
        return (
            f"subscription periods range from {sec(lo.period_us)} ({lo.name}) to "
            f"{sec(hi.period_us)} ({hi.name}): whatever the buffer size, one of them waits at "
            f"least {_half_seconds(hi.period_us - lo.period_us)} more or less than its period, "
            f"over the limit 3 x PING = {cap}"
        )
    i = int(m.argmin()) if hasattr(m, "argmin") else min(range(len(m)), key=m.__getitem__)
    best = i + first_n - 1
    return (
        f"with a publication period of {sec(pm_us)} the best buffer size n = {best + 1} "
        f"(n x pm = {sec((best + 1) * pm_us)}) still leaves a deviation of {sec(int(m[i]))}, "
        f"over the limit 3 x PING = {cap}"
    )


def _fronts(problem: BufferProblem) -> tuple[list[_Front | None], list[Infeasibility]]:
    """Per topic its front (None for a topic nobody subscribes to) and the
    topics the cap makes infeasible; then, when some are, the fronts of the
    problem with the cap lifted for those topics (:func:`solve_exact`)."""
    fronts, infeasible, _ = _fronts_both(problem)
    return fronts, infeasible


def _fronts_both(
    problem: BufferProblem,
    rows: list[Row] | None = None,
) -> tuple[list[_Front | None], list[Infeasibility], list[_Front | None]]:
    """The fronts, the infeasible topics and the fronts with the cap lifted
    for them, from one table per topic. All topics' tables are computed
    together in a few numpy operations over their concatenated candidate
    ranges (each topic alone costs more in numpy's per-call overhead than
    in arithmetic); the results are those of :func:`topic_table` and
    :func:`_front` topic by topic."""
    import numpy as np

    rows = _rows(problem) if rows is None else rows
    fronts: list[_Front | None] = [None] * len(problem.topics)
    relaxed: list[_Front | None] = [None] * len(problem.topics)
    infeasible: list[Infeasibility] = []
    if not rows:
        return fronts, infeasible, relaxed
    tables = _tables(problem, rows)
    caps = [problem.cap_for(topic) for _, topic, *_ in rows]
    m_all = tables[1]
    starts = tables[3]
    cap_arr = np.repeat(
        np.array([-1 if c is None else c for c in caps], dtype=np.int64), np.diff(starts)
    )
    uncapped = np.repeat(np.array([c is None for c in caps]), np.diff(starts))
    allowed = uncapped | (m_all <= cap_arr)
    any_allowed = np.logical_or.reduceat(allowed, starts[:-1])
    capped = _segment_fronts(tables, allowed)
    bad = [r for r, ok in enumerate(any_allowed) if not ok]
    if bad:
        everything = _segment_fronts(tables, np.repeat(~any_allowed, np.diff(starts)))
    for r, (i, topic, pm_us, subs, _, lo, _) in enumerate(rows):
        if any_allowed[r]:
            fronts[i] = relaxed[i] = capped[r]
            continue
        cap = caps[r]
        assert cap is not None
        m = m_all[starts[r] : starts[r + 1]]
        infeasible.append(
            Infeasibility(
                topic, tuple([x.name for x in subs]), _explain(topic, subs, pm_us, m, cap, lo)
            )
        )
        relaxed[i] = everything[r]
    return fronts, infeasible, relaxed


def _front_arrays(
    problem: BufferProblem,
    rows: list[Row],
) -> tuple[IntArray, IntArray, IntArray, IntArray, list[Infeasibility]]:
    """:func:`_fronts_both`'s fronts with the cap lifted for the infeasible
    topics, end to end as :func:`_concat` gives them (M, S, n, each row's
    start and the total), without one object per topic; and the infeasible
    topics. Every row's front has a point: a feasible row has an allowed
    size, an infeasible one all of its sizes."""
    import numpy as np

    tables = _tables(problem, rows)
    caps = [problem.cap_for(topic) for _, topic, *_ in rows]
    m_all, starts = tables[1], tables[3]
    lengths = np.diff(starts)
    cap_arr = np.repeat(np.array([-1 if c is None else c for c in caps], dtype=np.int64), lengths)
    uncapped = np.repeat(np.array([c is None for c in caps]), lengths)
    allowed = uncapped | (m_all <= cap_arr)
    any_allowed = np.logical_or.reduceat(allowed, starts[:-1])
    m, s, n, seg = _segment_front_arrays(tables, allowed)
    infeasible: list[Infeasibility] = []
    bad = np.flatnonzero(~any_allowed).tolist()
    if bad:
        parts = _segment_front_arrays(tables, np.repeat(~any_allowed, lengths))
        m, s, n, seg = (np.concatenate(pair) for pair in zip((m, s, n, seg), parts, strict=True))
        order = np.argsort(seg, kind="stable")  # rows in order, each row's points kept
        m, s, n, seg = m[order], s[order], n[order], seg[order]
        for r in bad:
            _, topic, pm_us, subs, _, lo, _ = rows[r]
            cap = caps[r]
            assert cap is not None
            infeasible.append(
                Infeasibility(
                    topic,
                    tuple([x.name for x in subs]),
                    _explain(topic, subs, pm_us, m_all[starts[r] : starts[r + 1]], cap, lo),
                )
            )
    bounds = np.searchsorted(seg, np.arange(len(rows) + 1, dtype=np.int64))
    return m, s, n, bounds, infeasible


Row = tuple[int, str, int, list[Subscription], list[int], int, int]


def _rows(problem: BufferProblem) -> list[Row]:
    """(topic index, topic, pm µs, its subscriptions, their periods sorted,
    lo, hi) of every subscribed topic, ``lo..hi`` narrowed to :func:`front_range`;
    BufferTooLarge past :data:`CANDIDATE_LIMIT` (counted over
    :func:`candidate_range`, the bound a model is told about)."""
    rows: list[Row] = []
    for i, (topic, pm_us, subs) in enumerate(
        zip(problem.topics, problem.publication_us, problem.periods_by_topic(), strict=True)
    ):
        if not subs:
            continue
        periods = sorted([x.period_us for x in subs])
        lo, hi = candidate_range(periods, pm_us, problem.max_buffer)
        if hi - lo + 1 > CANDIDATE_LIMIT:
            raise BufferTooLarge(topic, [x.name for x in subs], hi - lo + 1)
        rows.append((i, topic, pm_us, subs, periods, *front_range(periods, pm_us, lo, hi)))
    return rows


def front_range(periods_us: Sequence[int], pm_us: int, lo: int, hi: int) -> tuple[int, int]:
    """The part of ``lo..hi`` that holds every point of the topic's front
    (``periods_us`` sorted). M(n) and S(n) are convex in n: M is smallest
    where n x pm is nearest the middle of the periods, S where it is at a
    median. Left of both, a step to n + 1 makes M strictly smaller
    (n x pm < n' x pm <= middle) and S no larger (at or below the lower
    median), so n is dominated by n + 1, which sorts before it; right of
    both, the same with n - 1. Cutting those sizes leaves the front, the
    smallest M (for the infeasibility message) and the tie-breaks as they
    were, on far fewer candidates (709,724 -> 293,637 for 5,000 topics x
    25,000 subscriptions). Tested against the whole range in
    tests/plan/test_buffers_oracle.py."""
    k = len(periods_us)
    if k == 0:
        return lo, hi
    ends = periods_us[0] + periods_us[-1]  # twice the middle
    left = min(ends // (2 * pm_us), periods_us[(k - 1) // 2] // pm_us)
    right = max(-(-ends // (2 * pm_us)), -(-periods_us[k // 2] // pm_us))
    return min(max(lo, left), hi), max(min(hi, right), lo)


#: Candidate sizes (all topics together) up to which the sizes are computed
#: in plain Python: numpy's import (~0.3 s of CPU) is not worth it for a
#: small model (``modd plan`` of the paper's scenarios starts faster). Both
#: ways give the same sizes (tests/plan/test_buffers_oracle.py runs both).
SMALL_CANDIDATES = 4096

#: Largest candidate value (µs) and table count the batched computation's
#: encodings keep inside int64; beyond, topics are computed one by one.
_BATCH_VALUE_BITS = 42
_BATCH_ROWS_BITS = 20


def _tables(
    problem: BufferProblem, rows: Sequence[Row]
) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """S, M and n over every row's candidates, concatenated, with each row's
    start offset (and the total at the end)."""
    import numpy as np

    lengths = np.array([hi - lo + 1 for *_, lo, hi in rows], dtype=np.int64)
    starts = np.concatenate(([0], np.cumsum(lengths)))
    # every row's periods, sorted within the row, rows in order
    per_row = [r[4] for r in rows]
    big_ps = max(p[-1] for p in per_row)
    big_x = max(hi * pm for _, _, pm, *_, hi in rows)
    if (
        max(big_ps, big_x).bit_length() >= _BATCH_VALUE_BITS
        or len(rows).bit_length() >= _BATCH_ROWS_BITS
    ):
        parts = [
            topic_table(periods, pm, problem.max_buffer, lo, hi)
            for _, _, pm, _, periods, lo, hi in rows
        ]
        n = np.concatenate([np.arange(lo, hi + 1, dtype=np.int64) for *_, lo, hi in rows])
        s_all = np.concatenate([p[0] for p in parts])
        m_all = np.concatenate([p[1] for p in parts])
        if problem.alpha == 0:
            s_all = np.zeros_like(s_all)
        return s_all, m_all, n, starts
    seg = np.repeat(np.arange(len(rows), dtype=np.int64), lengths)
    offset = np.arange(starts[-1], dtype=np.int64) - starts[:-1][seg]
    n = np.array([lo for *_, lo, _ in rows], dtype=np.int64)[seg] + offset
    x = n * np.array([pm for _, _, pm, *_ in rows], dtype=np.int64)[seg]
    counts = np.array([len(p) for p in per_row], dtype=np.int64)
    ps = np.array([v for p in per_row for v in p], dtype=np.int64)
    ps_start = np.concatenate(([0], np.cumsum(counts)))
    ps_seg = np.repeat(np.arange(len(rows), dtype=np.int64), counts)
    prefix = np.concatenate(([0], np.cumsum(ps)))
    key_ps = (ps_seg << _BATCH_VALUE_BITS) + ps
    k_global = np.searchsorted(key_ps, (seg << _BATCH_VALUE_BITS) + x, side="right")
    first = ps_start[:-1][seg]
    k = k_global - first
    below = x * k - (prefix[k_global] - prefix[first])
    above = (prefix[ps_start[1:]][seg] - prefix[k_global]) - x * (counts[seg] - k)
    lo_ps = ps[ps_start[:-1]][seg]
    hi_ps = ps[ps_start[1:] - 1][seg]
    m_all = np.maximum(hi_ps - x, x - lo_ps)
    s_all = below + above
    if problem.alpha == 0:
        s_all = np.zeros_like(s_all)
    return s_all, m_all, n, starts


def _segment_fronts(
    tables: tuple[IntArray, IntArray, IntArray, IntArray], allowed: npt.NDArray[np.bool_]
) -> list[_Front | None]:
    """:func:`_front` of every row (None for a row with nothing allowed)."""
    import numpy as np

    m, s, n, seg = _segment_front_arrays(tables, allowed)
    rows = len(tables[3]) - 1
    bounds = np.searchsorted(seg, np.arange(rows + 1, dtype=np.int64))
    out: list[_Front | None] = []
    for r in range(rows):
        a, b = int(bounds[r]), int(bounds[r + 1])
        out.append(_Front(m[a:b], s[a:b], n[a:b]) if b > a else None)
    return out


def _segment_front_arrays(
    tables: tuple[IntArray, IntArray, IntArray, IntArray], allowed: npt.NDArray[np.bool_]
) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """Every row's front end to end: M, S, n and the row of each point (rows
    in order, each row's points as :func:`_front` orders them)."""
    import numpy as np

    s_all, m_all, n_all, starts = tables
    rows = len(starts) - 1
    seg_all = np.repeat(np.arange(rows, dtype=np.int64), np.diff(starts))
    s, m, n, seg = s_all[allowed], m_all[allowed], n_all[allowed], seg_all[allowed]
    # (row, M, S, n): rows and n are already in order, and lexsort is stable
    if len(m) and int(m.max()).bit_length() < _BATCH_VALUE_BITS and rows.bit_length() < 20:
        order = np.lexsort((s, (seg << _BATCH_VALUE_BITS) + m))
    else:
        order = np.lexsort((n, s, m, seg))
    s, m, n, seg = s[order], m[order], n[order], seg[order]
    # a point is kept when its S is below every S before it in its row: a
    # running minimum over S (or its dense ranks when S is too large) shifted
    # so that each row starts below all the rows before it
    top = int(s.max()) + 1 if len(s) else 1
    if top * (rows + 1) < 1 << 62:
        shifted = s + (rows - seg) * top
    else:
        _, rank = np.unique(s, return_inverse=True)
        shifted = rank.astype(np.int64).ravel() + (rows - seg) * (len(s) + 1)
    running = np.minimum.accumulate(shifted)
    keep = np.concatenate(([True], shifted[1:] < running[:-1]))[: len(s)]
    return m[keep], s[keep], n[keep], seg[keep]


def _concat(fronts: Sequence[_Front]) -> tuple[IntArray, IntArray, IntArray, IntArray]:
    """The fronts' M, S and n end to end, with each front's start offset
    (and the total at the end): one numpy operation over all topics instead
    of a few per topic."""
    import numpy as np

    lengths = np.array([len(f.m) for f in fronts], dtype=np.int64)
    starts = np.concatenate(([0], np.cumsum(lengths))).astype(np.int64)
    return (
        np.concatenate([f.m for f in fronts]),
        np.concatenate([f.s for f in fronts]),
        np.concatenate([f.n for f in fronts]),
        starts,
    )


def _last_at_most(m: IntArray, starts: IntArray, w: int) -> IntArray:
    """Per front (each M ascending, none empty): the index of its last point
    with M <= w, given that its first point has M <= w."""
    import numpy as np

    counts = np.add.reduceat((m <= w).astype(np.int64), starts[:-1])
    return starts[:-1] + counts - 1


def _best_w(fronts: Sequence[_Front], a: int, b: int) -> int:
    """The smallest w minimising a * sum_i min{S_i : M_i <= w} + b * w."""
    m, s, _, starts = _concat(fronts)
    return _best_w_of(m, s, starts, a, b)


def _best_w_of(m: IntArray, s: IntArray, starts: IntArray, a: int, b: int) -> int:
    """:func:`_best_w` of fronts given end to end (each front's start offset
    in ``starts``, the total at the end)."""
    import numpy as np

    w0 = int(m[starts[:-1]].max())
    f0 = sum(s[_last_at_most(m, starts, w0)].tolist())
    # the events: every point but a front's first with M > w0, and the
    # change of S it brings, in front order (as a concatenation per front)
    later = np.ones(len(m), dtype=bool)
    later[starts[:-1]] = False
    events = later & (m > w0)
    ev_m = m[events]
    if len(ev_m) == 0:
        return w0
    ds = np.concatenate(([0], np.diff(s)))[events]
    order = np.argsort(ev_m, kind="stable")
    ev_m = ev_m[order]
    ev_f = f0 + np.cumsum(ds[order])
    last = np.concatenate((ev_m[1:] != ev_m[:-1], [True]))  # last event at each w
    cand_w, cand_f = ev_m[last], ev_f[last]
    objective = [a * int(f) + b * int(w) for f, w in zip(cand_f, cand_w, strict=True)]
    i = int(np.argmin(objective))
    return int(cand_w[i]) if objective[i] < a * f0 + b * w0 else w0


def solve_exact(problem: BufferProblem) -> BufferSolution:
    """The MILP's optimum with the documented tie-break, exactly.

    When the cap makes it infeasible, returns the optimum with the cap lifted
    for the offending topics only, ``infeasible`` naming them."""
    rows = _rows(problem)
    if sum(hi - lo + 1 for *_, lo, hi in rows) <= SMALL_CANDIDATES:
        return _solve_small(problem)

    d = lcm(problem.alpha.denominator, problem.beta.denominator)
    a, b = int(problem.alpha * d), int(problem.beta * d)
    sizes = [1] * len(problem.topics)  # a topic nobody subscribes to
    infeasible: list[Infeasibility] = []
    if rows:
        # every row's front end to end (the cap lifted for the infeasible
        # topics): one front per subscribed topic, in topic order
        m, s, n, starts, infeasible = _front_arrays(problem, rows)
        w = _best_w_of(m, s, starts, a, b)
        chosen = n[_last_at_most(m, starts, w)].tolist()
        for (i, *_), size in zip(rows, chosen, strict=True):
            sizes[i] = size
    solution = solution_from_sizes(problem, sizes)
    if infeasible:
        return BufferSolution(solution.sizes, solution.deviations_us, tuple(infeasible))
    return solution


def _solve_small(problem: BufferProblem) -> BufferSolution:
    """:func:`solve_exact` in plain Python, for small models (the same steps
    on lists: tables, fronts, the sweep over w, the sizes)."""
    fronts: list[tuple[list[int], list[int], list[int]] | None] = [None] * len(problem.topics)
    infeasible: list[Infeasibility] = []
    for i, topic, pm_us, subs, ps, lo, hi in _rows(problem):
        first, last = ps[0], ps[-1]  # sorted
        xs = [n * pm_us for n in range(lo, hi + 1)]
        m = [max(last - x, x - first) for x in xs]
        s = [0] * len(xs) if problem.alpha == 0 else [sum(abs(p - x) for p in ps) for x in xs]
        cap = problem.cap_for(topic)
        allowed = [k for k, mk in enumerate(m) if cap is None or mk <= cap]
        if not allowed:
            assert cap is not None
            reason = _explain(topic, subs, pm_us, m, cap, lo)
            infeasible.append(Infeasibility(topic, tuple([x.name for x in subs]), reason))
            allowed = list(range(len(m)))  # the cap lifted for this topic
        fm: list[int] = []
        fs: list[int] = []
        fn: list[int] = []
        for mk, sk, nk in sorted((m[k], s[k], lo + k) for k in allowed):
            if not fs or sk < fs[-1]:
                fm.append(mk)
                fs.append(sk)
                fn.append(nk)
        fronts[i] = (fm, fs, fn)
    d = lcm(problem.alpha.denominator, problem.beta.denominator)
    a, b = int(problem.alpha * d), int(problem.beta * d)
    used = [f for f in fronts if f is not None]
    w = _best_w_small(used, a, b) if used else 0
    sizes = [1 if f is None else f[2][bisect_right(f[0], w) - 1] for f in fronts]
    solution = solution_from_sizes(problem, sizes)
    if infeasible:
        return BufferSolution(solution.sizes, solution.deviations_us, tuple(infeasible))
    return solution


def _best_w_small(fronts: Sequence[tuple[list[int], list[int], list[int]]], a: int, b: int) -> int:
    """:func:`_best_w` on lists."""
    w0 = max(f[0][0] for f in fronts)
    f0 = sum(f[1][bisect_right(f[0], w0) - 1] for f in fronts)
    events: list[tuple[int, int]] = [
        (fm[j], fs[j] - fs[j - 1]) for fm, fs, _ in fronts for j in range(1, len(fm)) if fm[j] > w0
    ]
    if not events:
        return w0
    events.sort(key=lambda e: e[0])  # stable, as the numpy sweep
    total = f0
    cands: list[tuple[int, int]] = []
    for k, (mk, dk) in enumerate(events):
        total += dk
        if k + 1 == len(events) or events[k + 1][0] != mk:  # the last event at each w
            cands.append((mk, total))
    objective = [a * f + b * w for w, f in cands]
    i = objective.index(min(objective))
    return cands[i][0] if objective[i] < a * f0 + b * w0 else w0
