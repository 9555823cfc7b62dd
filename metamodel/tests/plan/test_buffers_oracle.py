"""Buffer sizes: an independent brute-force oracle (every combination of n,
exact fractions, the documented lexicographic tie-break) against the exact
method and the cvxpy MILP, on seeded random small models, infeasible ones
included."""

from __future__ import annotations

import itertools
import random
from collections.abc import Sequence
from fractions import Fraction

import pytest
from modd_plan import buffers
from modd_plan.buffers import BufferProblem, BufferSolution, Subscription, solve_exact
from modd_plan.milp import solve_milp

PUB_US = [40_000, 100_000, 300_000, 500_000, 1_000_000, 70_000]
SUB_US = [
    100_000,
    250_000,
    500_000,
    1_000_000,
    1_500_000,
    2_000_000,
    3_000_000,
    5_000_000,
    8_000_000,
    330_000,
]
WEIGHTS = [Fraction(0), Fraction(1, 2), Fraction(1), Fraction(2), Fraction(3, 10)]
CAPS_US = [None, 300_000, 1_000_000, 2_490_000]


def random_problem(rng: random.Random) -> BufferProblem:
    n_topics = rng.randint(1, 3)
    topics = tuple(f"d.s.t{i}" for i in range(n_topics))
    subs = [
        Subscription(f"sub_{j}", rng.choice(topics), rng.choice(SUB_US))
        for j in range(rng.randint(0, 6))
    ]
    return BufferProblem(
        topics=topics,
        publication_us=tuple(rng.choice(PUB_US) for _ in topics),
        subscriptions=tuple(subs),
        max_buffer=rng.randint(1, 14 if n_topics == 3 else 40),
        cap_us=rng.choice(CAPS_US),
        alpha=rng.choice(WEIGHTS),
        beta=rng.choice(WEIGHTS),
    )


def _devs(p: BufferProblem, sizes: Sequence[int]) -> dict[str, int]:
    n = dict(zip(p.topics, sizes, strict=True))
    pm = dict(zip(p.topics, p.publication_us, strict=True))
    return {s.name: abs(s.period_us - n[s.topic] * pm[s.topic]) for s in p.subscriptions}


def _key(p: BufferProblem, sizes: Sequence[int]) -> tuple[object, ...]:
    """(objective, w, then per topic its max deviation and n)."""
    devs = _devs(p, sizes)
    w = max(devs.values(), default=0)
    key: list[object] = [p.alpha * sum(devs.values()) + p.beta * w, w]
    for topic, n in zip(p.topics, sizes, strict=True):
        own = [devs[s.name] for s in p.subscriptions if s.topic == topic]
        key += [max(own, default=0), n]
    return tuple(key)


def oracle(p: BufferProblem) -> tuple[dict[str, int], list[str]]:
    """Sizes by brute force, and the topics the cap makes infeasible."""
    grid = list(itertools.product(range(1, p.max_buffer + 1), repeat=len(p.topics)))
    cap = p.cap_us
    infeasible = [
        t
        for t in p.topics
        if cap is not None
        and any(s.topic == t for s in p.subscriptions)
        and not any(
            all(abs(s.period_us - n * pm) <= cap for s in p.subscriptions if s.topic == t)
            for n in range(1, p.max_buffer + 1)
            for pm in [p.publication_us[p.topics.index(t)]]
        )
    ]
    if cap is not None:  # the cap binds every topic but the infeasible ones
        bound = [s.name for s in p.subscriptions if s.topic not in infeasible]
        grid = [g for g in grid if all(_devs(p, g)[name] <= cap for name in bound)]
    best = min(grid, key=lambda g: _key(p, g))
    return dict(zip(p.topics, best, strict=True)), infeasible


def _check(p: BufferProblem, got: BufferSolution) -> None:
    sizes, infeasible = oracle(p)
    assert got.sizes == sizes, p
    assert [x.topic for x in got.infeasible] == infeasible, p
    assert got.deviations_us == _devs(p, list(sizes.values()))


def _problems(seed: int, count: int) -> list[BufferProblem]:
    rng = random.Random(seed)
    return [random_problem(rng) for _ in range(count)]


def test_random_problems_cover_the_interesting_cases() -> None:
    problems = _problems(1, 300)
    assert sum(bool(oracle(p)[1]) for p in problems) >= 20  # infeasible ones
    mixed = [  # an infeasible topic beside a subscribed one that must keep the cap
        p
        for p in problems
        if oracle(p)[1] and {s.topic for s in p.subscriptions} - set(oracle(p)[1])
    ]
    assert len(mixed) >= 10
    assert sum(p.alpha == 0 or p.beta == 0 for p in problems) >= 50
    assert sum(len(p.topics) == 3 and len(p.subscriptions) >= 4 for p in problems) >= 30


@pytest.mark.parametrize("way", ["python", "numpy"])
@pytest.mark.parametrize("chunk", range(6))
def test_exact_method_matches_brute_force(
    chunk: int, way: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Both ways of the exact method: plain Python (small models) and the
    batched numpy tables (forced here with a threshold of 0)."""
    if way == "numpy":
        monkeypatch.setattr(buffers, "SMALL_CANDIDATES", 0)
    for p in _problems(1, 300)[chunk * 50 : (chunk + 1) * 50]:
        _check(p, solve_exact(p))


def test_both_ways_agree_on_larger_random_problems(monkeypatch: pytest.MonkeyPatch) -> None:
    """Beyond brute force: the plain-Python and numpy ways give the same
    solution on problems of a few thousand candidates, caps and zero weights
    included."""
    rng = random.Random(11)
    for _ in range(40):
        topics = tuple(f"d.s.t{i}" for i in range(rng.randint(1, 12)))
        p = BufferProblem(
            topics=topics,
            publication_us=tuple(rng.choice(PUB_US) for _ in topics),
            subscriptions=tuple(
                Subscription(f"s{j}", rng.choice(topics), rng.choice(SUB_US))
                for j in range(rng.randint(0, 60))
            ),
            max_buffer=rng.choice([5, 50, 1000]),
            cap_us=rng.choice(CAPS_US),
            alpha=rng.choice(WEIGHTS),
            beta=rng.choice(WEIGHTS),
        )
        monkeypatch.setattr(buffers, "SMALL_CANDIDATES", 10**9)
        small = solve_exact(p)
        monkeypatch.setattr(buffers, "SMALL_CANDIDATES", 0)
        assert solve_exact(p) == small, p


@pytest.mark.parametrize("chunk", range(4))
def test_cvxpy_milp_matches_brute_force(chunk: int) -> None:
    for p in _problems(2, 200)[chunk * 50 : (chunk + 1) * 50]:
        _check(p, solve_milp(p))


def test_exact_and_milp_agree_on_a_larger_random_problem() -> None:
    rng = random.Random(7)
    topics = tuple(f"d.s.t{i}" for i in range(40))
    p = BufferProblem(
        topics=topics,
        publication_us=tuple(rng.choice(PUB_US) for _ in topics),
        subscriptions=tuple(
            Subscription(f"s{j}", rng.choice(topics), rng.choice(SUB_US)) for j in range(300)
        ),
        max_buffer=1000,
        cap_us=None,
        alpha=Fraction(1),
        beta=Fraction(1),
    )
    exact, milp = solve_exact(p), solve_milp(p)
    assert exact.sizes == milp.sizes
    assert exact.objective(p.alpha, p.beta) == milp.objective(p.alpha, p.beta)
    some_optimum = solve_milp(p, tie_break=False)  # the paper's MILP alone
    assert some_optimum.objective(p.alpha, p.beta) == exact.objective(p.alpha, p.beta)


def test_exact_and_milp_agree_on_medium_random_problems() -> None:
    """Beyond brute force: up to 12 topics x 60 subscriptions, MAX_BUFFER up to
    1000, caps, zero weights; sizes and infeasibility must be identical."""
    rng = random.Random(5)
    for _ in range(15):
        topics = tuple(f"t{i}" for i in range(rng.randint(2, 12)))
        p = BufferProblem(
            topics=topics,
            publication_us=tuple(rng.choice([*PUB_US, 10_000, 33_000]) for _ in topics),
            subscriptions=tuple(
                Subscription(f"s{j}", rng.choice(topics), rng.choice([*SUB_US, 2_300_000]))
                for j in range(rng.randint(1, 60))
            ),
            max_buffer=rng.choice([10, 100, 1000]),
            cap_us=rng.choice([None, 1_000_000, 2_490_000]),
            alpha=rng.choice(WEIGHTS),
            beta=rng.choice(WEIGHTS),
        )
        exact, milp = solve_exact(p), solve_milp(p)
        assert (exact.sizes, exact.infeasible) == (milp.sizes, milp.infeasible), p


def test_front_range_keeps_the_whole_front() -> None:
    """The narrowed candidate range (front_range) against the whole one: the
    same Pareto front (M, S, n), the same smallest M and the same first size
    reaching it, on random topics, caps and zero weights included."""
    import numpy as np

    rng = random.Random(5)
    narrower = 0
    for _ in range(2000):
        pm = rng.choice(PUB_US + [10_000, 1_000, 37_000])
        periods = sorted(
            rng.choice(SUB_US + [rng.randrange(1_000, 9_000_000)]) for _ in range(rng.randint(1, 9))
        )
        lo, hi = buffers.candidate_range(periods, pm, rng.choice([3, 50, 10**6]))
        a, b = buffers.front_range(periods, pm, lo, hi)
        assert lo <= a <= b <= hi
        narrower += (b - a) < (hi - lo)
        cap = rng.choice(CAPS_US)
        for zero_s in (False, True):
            fronts = []
            for first, last in ((lo, hi), (a, b)):
                s, m = buffers.topic_table(periods, pm, hi, first, last)
                if zero_s:
                    s = np.zeros_like(s)
                allowed = np.ones(len(m), dtype=bool) if cap is None else m <= cap
                front = buffers._front(s, m, allowed, first) if allowed.any() else None
                best = (int(m.min()), int(m.argmin()) + first)
                fronts.append(
                    (
                        best,
                        None
                        if front is None
                        else (front.m.tolist(), front.s.tolist(), front.n.tolist()),
                    )
                )
            assert fronts[0] == fronts[1], (periods, pm, lo, hi, cap)
    assert narrower > 500
