"""The slot count without an exponential step: the lattice sieve against the
previous algorithm (inclusion–exclusion over every subset, kept here as the
oracle) and a brute-force listing on random period sets; adversarial period
sets (e non-dividing periods) either counted within the bound or refused,
fast, with the subscriptions named."""

from __future__ import annotations

import time
from fractions import Fraction
from math import lcm, prod
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from modd_plan import schedule as sched_mod
from modd_plan.plan import PlanningError, make_plan
from modd_plan.schedule import (
    LATTICE_LIMIT,
    Schedule,
    ScheduleTooLarge,
    coprime_base,
    essential_periods,
)

PRIMES = [p for p in range(2, 600) if all(p % q for q in range(2, int(p**0.5) + 1))]


def oracle_coefficients(periods: list[int]) -> dict[int, int]:
    """The planner's previous count: inclusion–exclusion over all 2^e - 1
    subsets of the essential periods, merged by LCM (exponential in e)."""
    distinct = sorted(set(periods))
    essential = [p for i, p in enumerate(distinct) if all(p % q for q in distinct[:i])]
    coef: dict[int, int] = {}
    for p in essential:
        new = dict(coef)
        new[p] = new.get(p, 0) + 1
        for d, c in coef.items():
            m = lcm(d, p)
            new[m] = new.get(m, 0) - c
        coef = {d: c for d, c in new.items() if c}
    return coef


def oracle_count(periods: list[int], t: int) -> int:
    return sum(c * (t // d) for d, c in oracle_coefficients(periods).items())


periods_st = st.lists(
    st.builds(lambda a, b: a * b, st.integers(1, 90), st.sampled_from([1, 2, 6, 10, 100, 10_000])),
    min_size=1,
    max_size=10,
)


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(periods=periods_st, mult=st.integers(1, 4), data=st.data())
def test_count_matches_the_previous_algorithm(periods: list[int], mult: int, data: Any) -> None:
    hyper = lcm(*periods) * mult
    s = Schedule.from_periods_us(periods, hyper)
    assert s.messages_per_hyperperiod == oracle_count(periods, hyper)
    t = data.draw(st.integers(0, 3 * hyper))
    assert s.count_until(t) == oracle_count(periods, t)
    k = data.draw(st.integers(0, 3 * s.messages_per_hyperperiod))
    index, date, due = next(s.iter_due_periods(k))
    assert index == k
    assert oracle_count(periods, date) == k + 1 and oracle_count(periods, date - 1) == k
    assert due == [p for p in sorted(set(periods)) if date % p == 0]


@settings(max_examples=200, deadline=None)
@given(periods=st.lists(st.integers(1, 60), min_size=1, max_size=7))
def test_count_matches_a_listing(periods: list[int]) -> None:
    hyper = lcm(*periods)
    if hyper > 200_000:
        return
    dates = {d for p in periods for d in range(p, hyper + 1, p)}
    assert Schedule.from_periods_us(periods).messages_per_hyperperiod == len(dates)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(1, 10**6), min_size=1, max_size=12))
def test_coprime_base(numbers: list[int]) -> None:
    base = coprime_base(numbers)
    assert all(b > 1 for b in base)
    assert all(lcm(a, b) == a * b for i, a in enumerate(base) for b in base[i + 1 :])
    for n in numbers:
        for b in base:
            while n % b == 0:
                n //= b
        assert n == 1


def test_essential_periods() -> None:
    assert essential_periods([6, 4, 2, 9, 3, 12, 35]) == [2, 3, 35]


def pair_cycle(e: int) -> list[int]:
    """e pairwise non-dividing periods chained by shared primes (one group)."""
    return [PRIMES[i] * PRIMES[(i + 1) % e] * 1000 for i in range(e)]


ADVERSARIAL = {
    "primes": lambda e: [p * 10_000 for p in PRIMES[1 : e + 1]],
    "0.1 s grid": lambda e: [p * 100_000 for p in PRIMES[1 : e + 1]],
    "consecutive": lambda e: [k * 1000 for k in range(e, 2 * e)],
    "pair cycle": pair_cycle,
}


@pytest.mark.parametrize("kind", sorted(ADVERSARIAL))
@pytest.mark.parametrize("e", [8, 12, 16, 24, 40])
def test_adversarial_period_sets_are_bounded(kind: str, e: int) -> None:
    periods = ADVERSARIAL[kind](e)
    start = time.process_time()
    try:
        count: int | None = Schedule.from_periods_us(periods).messages_per_hyperperiod
    except ScheduleTooLarge as exc:
        count = None
        assert set(exc.periods_us) <= set(periods) and len(exc.periods_us) > 1
    elapsed = time.process_time() - start
    if e <= 12 or kind != "pair cycle":
        assert count is not None
    if e <= 12:
        assert count == oracle_count(periods, lcm(*periods))
    assert elapsed < 1.0  # about 75 ms at worst here


def test_small_bound_refuses_and_names_the_group(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(sched_mod, "LATTICE_LIMIT", 1 << 8)
    monkeypatch.setattr(sched_mod, "SUBSET_LIMIT", 1 << 4)
    periods = pair_cycle(10) + [37_000, 41_000]  # a second, innocent group
    with pytest.raises(ScheduleTooLarge) as info:
        Schedule.from_periods_us(periods).messages_per_hyperperiod  # noqa: B018
    assert set(info.value.periods_us) == set(pair_cycle(10))
    assert "lattice cells" in str(info.value)


def test_lattice_limit_is_the_documented_one() -> None:
    assert LATTICE_LIMIT == 1 << 20


def test_too_many_essential_periods() -> None:
    periods = [p * 1000 for p in PRIMES[:120]]
    with pytest.raises(ScheduleTooLarge):
        essential_periods([p for p in range(10_000, 10_600)])
    assert Schedule.from_periods_us(periods).messages_per_hyperperiod > 0


def test_planning_error_is_located_at_the_subscriptions(make_model: Any) -> None:
    cycle = [f"{PRIMES[i] * PRIMES[(i + 1) % 24] / 1000:.3f}" for i in range(24)]
    names = [f"v{i}" for i in range(24)]
    subs = [(f"sub{i}", names[i], p, "MAX") for i, p in enumerate(cycle)]
    subs.append(("calm", names[0], "0.101", "MAX"))  # coprime to the cycle: not named
    model = make_model(names, [("p", "0.001", names)], subs)
    start = time.process_time()
    with pytest.raises(PlanningError) as info:
        make_plan(model)
    assert time.process_time() - start < 1.0
    diags = info.value.diagnostics
    pointers = {d.pointer for d in diags}
    assert pointers == {f"/subscribers/{i}/periodS" for i in range(24)}
    assert all("lattice cells" in d.message for d in diags)
    assert "subscriber 'sub0'" in diags[0].message
    assert isinstance(info.value, ValueError)  # callers catching ValueError still do


def test_prime_periods_on_a_grid_plan_fast(make_model: Any) -> None:
    """e = 24 pairwise coprime periods on a 0.1 s grid (the old count: 2^24
    terms, minutes and gigabytes): counted in milliseconds."""
    names = [f"v{i}" for i in range(24)]
    subs = [(f"sub{i}", names[i], f"{p / 10:.1f}", "MAX") for i, p in enumerate(PRIMES[1:25])]
    model = make_model(names, [("p", "0.1", names)], subs)
    start = time.process_time()
    j = make_plan(model).to_json()
    assert time.process_time() - start < 1.0
    units = PRIMES[1:25]
    h = 1
    for u in units:
        h *= u
    unhit = 1
    for u in units:
        unhit *= u - 1
    assert j["messages_per_hyperperiod"] == h - unhit  # pairwise coprime: a product
    assert j["schedule"]["slots_truncated"]
    assert Fraction(j["hyperperiod_s"]) == Fraction(h, 10)  # 35 digits: once rounded to 28


def test_cli_prints_the_located_error(make_model: Any, tmp_path: Any, capsys: Any) -> None:
    import argparse

    from modd_model import dumps
    from modd_plan.cli import run_plan

    cycle = [f"{PRIMES[i] * PRIMES[(i + 1) % 24] / 1000:.3f}" for i in range(24)]
    names = [f"v{i}" for i in range(24)]
    subs = [(f"sub{i}", names[i], p, "MAX") for i, p in enumerate(cycle)]
    path = tmp_path / "worst.modd"
    path.write_text(dumps(make_model(names, [("p", "0.001", names)], subs), "modd"))
    args = argparse.Namespace(
        file=str(path),
        json=False,
        ping=None,
        alpha=None,
        beta=None,
        max_buffer=None,
        method="exact",
    )
    assert run_plan(args) == 1
    err = capsys.readouterr().err
    lines = [x for x in err.splitlines() if ": error: subscriber 'sub" in x]
    assert len(lines) == 24 and all(x.startswith(f"{path}:") for x in lines)
    line = int(lines[0].split(":")[1])
    assert "sub0" in path.read_text().splitlines()[line - 1]


def test_max_buffer_is_bounded_and_costs_nothing(scenario1_dict: Any) -> None:
    """maxBuffer has a schema maximum; the planner's memory does not depend on
    it (the old one: 840 MiB at 1e7, 4.8 GiB at 1e8)."""
    import resource

    from modd_model import validate

    model = dict(scenario1_dict, link={"maxBuffer": 10**8})
    diags = [d for d in validate(model) if d.severity == "error"]
    assert [d.pointer for d in diags] == ["/link/maxBuffer"]
    assert "1000000" in diags[0].message
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    start = time.process_time()
    plan = make_plan(scenario1_dict, max_buffer=10**8)
    assert time.process_time() - start < 1.0
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50_000  # KiB
    assert plan.buffer_sizes == make_plan(scenario1_dict).buffer_sizes


def test_buffer_candidates_beyond_the_bound_are_a_located_error(make_model: Any) -> None:
    model = make_model(
        ["a", "b"],
        [("p", "0.000001", ["a", "b"])],
        [
            ("fast", "a", "0.001", "MAX"),
            ("slow", "a", "100000", "MAX"),
            ("fine", "b", "1.0", "MAX"),
        ],
        link={"maxBuffer": 10**6},
    )
    start = time.process_time()
    with pytest.raises(PlanningError) as info:
        make_plan(model)
    assert time.process_time() - start < 1.0
    diags = info.value.diagnostics
    assert [d.pointer for d in diags] == ["/subscribers/0/periodS", "/subscribers/1/periodS"]
    assert "candidate buffer sizes" in diags[0].message


def test_periods_and_decimals_are_bounded(scenario1_dict: Any) -> None:
    from modd_model import validate

    model = dict(scenario1_dict)
    model["subscribers"] = [dict(s) for s in model["subscribers"]]
    model["subscribers"][0]["periodS"] = "2000000"
    model["subscribers"][1]["periodS"] = "0." + "5" * 30
    errors = {d.pointer: d.message for d in validate(model) if d.severity == "error"}
    assert "at most 1,000,000 s" in errors["/subscribers/0/periodS"]
    assert "/subscribers/1/periodS" in errors


def _grid_model(make_model: Any, n_topics: int, n_subs: int) -> Any:
    """The bench's ``grid:T:N``: periods drawn from primes x 0.1 s (0.3 ...
    11.3 s, 29 of them), published every 0.1 s; hyperperiod about 10^45 s."""
    grid = [f"{p / 10:.1f}" for p in PRIMES[1:30]]
    names = [f"v{i}" for i in range(n_topics)]
    subs = [
        (f"sub{k}", names[k % n_topics], grid[k % len(grid)], ("MIN", "MAX", "AVERAGE")[k % 3])
        for k in range(n_subs)
    ]
    return make_model(names, [("p", "0.1", names)], subs)


@pytest.mark.parametrize("case", ["e:primes:40", "e:grid:40", "grid:100:500"])
def test_hyperperiods_past_forty_digits_make_valid_plans(make_model: Any, case: str) -> None:
    """The bench's cases whose hyperperiod has 45-70 digits (10^39-10^64 s):
    the runtime never materialises the hyperperiod, so the plan is written
    whole, its hyperperiod exact (it ended in "number out of range")."""
    from modd_contracts.schema import validate as check_contract

    if case == "grid:100:500":
        model, units, scale = _grid_model(make_model, 100, 500), PRIMES[1:30], 100_000
    else:
        units = PRIMES[1:41]
        scale = 10_000 if case == "e:primes:40" else 100_000
        names = [f"v{i}" for i in range(40)]
        subs = [
            (f"sub{i}", names[i], f"{p * scale / 10**6:.2f}", "MAX") for i, p in enumerate(units)
        ]
        model = make_model(names, [("p", "0.01", names)], subs)
    start = time.process_time()
    j = make_plan(model).to_json()
    assert time.process_time() - start < 2.0  # ~25 ms idle
    assert check_contract("plan", j) == []
    assert len(j["hyperperiod_s"]) > 40
    assert Fraction(j["hyperperiod_s"]) == Fraction(scale * prod(units), 10**6)
    unhit = prod(u - 1 for u in units)
    assert j["messages_per_hyperperiod"] == prod(units) - unhit  # pairwise coprime
    assert Fraction(j["schedule"]["slots"][0]["date_s"]) == Fraction(3 * scale, 10**6)


def test_hyperperiod_past_the_bound_is_a_located_error(make_model: Any) -> None:
    """Past 2^HYPERPERIOD_BITS_LIMIT µs: refused while the LCM is built."""
    from modd_plan.plan import HYPERPERIOD_BITS_LIMIT

    units = [p for p in range(7, 1500) if all(p % q for q in range(2, int(p**0.5) + 1))][:150]
    # coprime to 10 and to one another: no period divides another
    assert prod(units).bit_length() > HYPERPERIOD_BITS_LIMIT
    names = [f"v{i}" for i in range(len(units))]
    subs = [(f"sub{i}", names[i], f"{p / 1000:.3f}", "MAX") for i, p in enumerate(units)]
    model = make_model(names, [("p", "0.001", names)], subs)
    start = time.process_time()
    with pytest.raises(PlanningError) as info:
        make_plan(model)
    assert time.process_time() - start < 1.0
    diags = info.value.diagnostics
    assert diags and all(d.pointer.startswith("/subscribers/") for d in diags)
    assert diags[0].pointer == "/subscribers/0/periodS" and "hyperperiod" in diags[0].message
