"""The plan of a model: streams, schedule, buffer sizes, delays, link cost.

One function, :func:`make_plan`, used by the backend (live), the generators
and the SubBroker (at run time, with the measured PING):

>>> plan = make_plan(model)                                # doctest: +SKIP
>>> plan.buffer_sizes["usv.accelerometer.accel_x"]         # doctest: +SKIP
28
>>> plan.to_json()["messages_per_hyperperiod"]             # doctest: +SKIP
8
"""

from __future__ import annotations

import gc
from collections.abc import Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, replace
from fractions import Fraction
from functools import lru_cache
from math import lcm
from typing import Any

from modd_contracts.types_gen import PlanDocument
from modd_model.diagnostics import Diagnostic, ModelError
from modd_model.numbers import MICROS_PER_SECOND, fraction_to_decimal
from modd_model.query import Topic, link_settings, topics

from .buffers import (
    BufferProblem,
    BufferSolution,
    BufferTooLarge,
    Infeasibility,
    Subscription,
    solve_exact,
)
from .calibration import Calibration
from .control import ControlInputs
from .linkbudget import LinkBudget, LinkSettings, link_budget
from .linkcost import LinkCost, plain_message_bytes, predict, window_value_bytes
from .planjson import plan_to_json
from .proposals import Proposal, propose
from .radio import RadioProfile, RadioReport, radio_report
from .resolution import calibration_use, quantised_window_bytes
from .schedule import Schedule, ScheduleTooLarge
from .streams import (
    PlannedStream,
    Price,
    StreamKey,
    asked_streams,
    period_of,
    plan_streams,
)

METHODS = ("exact", "cvxpy")

#: Cap on the hyperperiod's size (bits of its microseconds): far beyond any
#: mission (2^1024 µs), it only bounds the cost of the big-integer arithmetic.
HYPERPERIOD_BITS_LIMIT = 1024


class PlanningError(ModelError, ValueError):
    """A valid model the planner cannot plan within its bounds on work and
    memory; the diagnostics point at the subscriptions that cause it."""


def _us(period: Fraction) -> int:
    return _us_of(period.numerator, period.denominator)


def _key_us(key: StreamKey) -> int:
    """A stream's period in µs (its numerator and denominator are cached)."""
    return _us_of(*key._nd)  # type: ignore[attr-defined]


@lru_cache(maxsize=65_536)  # bounded, keyed by integers: Fraction hashing is slow
def _us_of(numerator: int, denominator: int) -> int:
    us, rest = divmod(numerator * MICROS_PER_SECOND, denominator)
    if rest:
        raise ValueError(
            f"{Fraction(numerator, denominator)} s is not a whole number of microseconds"
        )
    return us


@lru_cache(maxsize=65_536)  # bounded: a model repeats few period texts
def _text_us(text: str) -> int:
    return _us(period_of(text))


def _seconds(us: int) -> str:
    return fraction_to_decimal(Fraction(us, MICROS_PER_SECOND))


@dataclass(frozen=True)
class PlannerConstants:
    """MAX_BUFFER, PING (s), alpha, beta: from the model's link, or overridden."""

    max_buffer: int
    ping_s: Fraction
    alpha: Fraction
    beta: Fraction

    @property
    def cap_us(self) -> int:
        """3 x PING in whole microseconds (deviations are whole µs)."""
        return int(3 * self.ping_s * MICROS_PER_SECOND)

    def to_json(self) -> dict[str, Any]:
        return {
            "max_buffer": self.max_buffer,
            "ping_s": fraction_to_decimal(self.ping_s),
            "alpha": fraction_to_decimal(self.alpha),
            "beta": fraction_to_decimal(self.beta),
            "delay_cap_s": _seconds(self.cap_us),
        }


def constants_for(
    model: Mapping[str, Any],
    *,
    ping_s: Fraction | None = None,
    alpha: Fraction | None = None,
    beta: Fraction | None = None,
    max_buffer: int | None = None,
) -> PlannerConstants:
    """The model's planner constants (paper defaults), with overrides."""
    link = link_settings(dict(model))
    return PlannerConstants(
        max_buffer=link.max_buffer if max_buffer is None else max_buffer,
        ping_s=link.ping_s if ping_s is None else ping_s,
        alpha=link.alpha if alpha is None else alpha,
        beta=link.beta if beta is None else beta,
    )


@dataclass(frozen=True)
class Plan:
    """Everything the brokers and the UI need, computed once."""

    topics: tuple[Topic, ...]
    streams: tuple[PlannedStream, ...]
    subscriptions: dict[str, StreamKey]
    schedule: Schedule
    buffers: BufferSolution
    unpublished: tuple[Infeasibility, ...]
    constants: PlannerConstants
    link: LinkCost
    budget: LinkBudget | None = None  # the declared transport's budget (linkbudget.py)
    radio: RadioReport | None = None  # the declared radio's figures (radio.py)
    proposals: tuple[Proposal, ...] = ()  # when the radio refuses it (proposals.py)

    @property
    def sent_streams(self) -> list[PlannedStream]:
        """Sent streams in id order."""
        return sorted((s for s in self.streams if s.id is not None), key=lambda s: s.id or 0)

    @property
    def buffer_sizes(self) -> dict[str, int]:
        return dict(self.buffers.sizes)

    @property
    def delays(self) -> dict[str, Fraction]:
        """Per subscriber |ps - n * pm| in seconds."""
        return {k: Fraction(v, MICROS_PER_SECOND) for k, v in self.buffers.deviations_us.items()}

    @property
    def infeasible(self) -> tuple[Infeasibility, ...]:
        return self.unpublished + self.buffers.infeasible

    def stream(self, key: str) -> PlannedStream:
        """The planned stream with this key (KeyError if none)."""
        for s in self.streams:
            if s.stream.key == key:
                return s
        raise KeyError(key)

    def to_json(self) -> PlanDocument:
        """The plan as one JSON object (see docs/planning.md), typed by its contract."""
        with gc_paused():
            return plan_to_json(self)


def buffer_problem(
    model: Mapping[str, Any], tops: Mapping[str, Topic], constants: PlannerConstants
) -> tuple[BufferProblem, tuple[Infeasibility, ...]]:
    """The buffer-size MILP's data for a model (published topics only), and
    the subscriptions to unpublished topics, which no buffer can serve."""
    published = [t for t in tops.values() if t.period is not None]
    subs: list[Subscription] = []
    orphans: dict[str, list[str]] = {}
    for sub in model.get("subscribers", []):
        topic = tops.get(sub["topic"])
        if topic is None or topic.period is None:
            orphans.setdefault(sub["topic"], []).append(sub["name"])
        else:
            subs.append(Subscription(sub["name"], sub["topic"], _text_us(sub["periodS"])))
    problem = BufferProblem(
        topics=tuple(t.name for t in published),
        publication_us=tuple(_us(t.period) for t in published if t.period is not None),
        subscriptions=tuple(subs),
        max_buffer=constants.max_buffer,
        cap_us=constants.cap_us,
        alpha=constants.alpha,
        beta=constants.beta,
    )
    unpublished = tuple(
        Infeasibility(t, tuple(names), "no publisher publishes this topic")
        for t, names in orphans.items()
    )
    return problem, unpublished


def _window_bytes(stream: StreamKey, tops: Mapping[str, Topic]) -> Fraction:
    topic = tops.get(stream.topic)
    (pn, pd) = stream._nd  # type: ignore[attr-defined]
    if topic is None or topic.period is None:
        return window_value_bytes(stream.aggregation, "float32", Fraction(0), _us_of(pn, pd))
    pm = topic.period
    return _bytes(
        stream.aggregation, topic.type, pn * pm.denominator, pd * pm.numerator, _us_of(pn, pd)
    )


@lru_cache(maxsize=65_536)  # keyed by integers: Fraction hashing is slow
def _bytes(
    aggregation: str, topic_type: str, samples_num: int, samples_den: int, period_us: int = 0
) -> Fraction:
    return window_value_bytes(
        aggregation, topic_type, Fraction(samples_num, samples_den), period_us
    )


@lru_cache(maxsize=65_536)  # keyed by integers: a plan repeats few (period, topic) kinds
def _cost(
    aggregation: str, topic_type: str, p_num: int, p_den: int, pm_num: int, pm_den: int
) -> float:
    """Value bytes per second of a stream of period p on a topic of period pm."""
    window = _bytes(aggregation, topic_type, p_num * pm_den, p_den * pm_num, _us_of(p_num, p_den))
    return float(window / Fraction(p_num, p_den))


def _link_cost(
    model: Mapping[str, Any],
    sched: Schedule,
    window_bytes: list[Fraction],
    tops: Mapping[str, Topic],
) -> LinkCost:
    plain: dict[str, tuple[Fraction, int]] = {}
    per_topic: dict[str, tuple[Fraction, int] | None] = {}  # computed once per topic
    for sub in model.get("subscribers", []):
        name = sub["topic"]
        if name in per_topic:
            entry = per_topic[name]
        else:
            topic = tops.get(name)
            entry = per_topic[name] = (
                (topic.period, plain_message_bytes(topic.name, topic.type))
                if topic is not None and topic.period is not None
                else None
            )
        if entry is not None:
            plain[sub["name"]] = entry
    return predict(sched, window_bytes, plain)


def _budget(
    model: Mapping[str, Any],
    sched: Schedule,
    sent: list[PlannedStream],
    streams: Sequence[PlannedStream],
    window_bytes: list[Fraction],
    carry: bool = False,
    status_period_s: int | None = None,
    status_horizon_s: int | None = None,
) -> LinkBudget:
    # by identity: plan_streams gives each stream one key object, which its
    # derived streams' sources hold (no StreamKey hashed or compared)
    served: dict[int, list[str]] = {id(s.stream): list(s.subscribers) for s in sent}
    for s in streams:
        if s.id is not None or not s.subscribers:
            continue  # a sent stream has no sources; nobody to add
        for src in s.sources:
            names = served.get(id(src.stream))
            if names is not None:
                names += [n for n in s.subscribers if n not in names]
    return link_budget(
        LinkSettings.of(model),
        sched,
        window_bytes,
        [served[id(s.stream)] for s in sent],
        [sub["name"] for sub in model.get("subscribers", [])],
        carry,
        ControlInputs.of(model, status_period_s, status_horizon_s),
    )


def _solve_buffers(problem: BufferProblem, method: str) -> BufferSolution:
    if method == "cvxpy":
        from .milp import solve_milp  # imports cvxpy (0.6 s) on first use only

        return solve_milp(problem)
    return solve_exact(problem)


def make_plan(
    model: Mapping[str, Any],
    *,
    ping_s: Fraction | None = None,
    alpha: Fraction | None = None,
    beta: Fraction | None = None,
    max_buffer: int | None = None,
    method: str = "exact",
    proposals: bool = True,
    calibration: Calibration | None = None,
    status_period_s: int | None = None,
    status_horizon_s: int | None = None,
) -> Plan:
    """Plan a validated model. ``method`` picks the buffer-size solver:
    ``"exact"`` (fast, default) or ``"cvxpy"`` (the MILP with HiGHS); both
    give the same sizes. Overrides replace the model's planner constants.
    A plan over its radio's duty-cycle limit carries the nearest plans that
    fit (``proposals=False``: not searched). ``calibration``: quantised
    values sized from an archive's samples (calibration.py), the proposals'
    too. ``status_period_s``: the STATUS period the SubBroker asks for
    (None: its default), in the control traffic (control.py); ``status_horizon_s``:
    the length of run whose STATUS frames are estimated (None: the first hour)."""
    if method not in METHODS:
        raise ValueError(f"unknown method {method!r}; expected one of {METHODS}")
    options = _Options(
        ping_s, alpha, beta, max_buffer, method, calibration, status_period_s, status_horizon_s
    )
    with gc_paused():
        plan = _make_plan(model, options)
        if not proposals or plan.radio is None or plan.radio.fits:
            return plan

        def replan(candidate: Mapping[str, Any]) -> tuple[RadioReport, float] | None:
            try:
                p = _make_plan(candidate, options)
            except PlanningError:
                return None
            if p.radio is None or p.budget is None or len(p.infeasible) > len(plan.infeasible):
                return None  # a candidate must not break the delay cap the plan meets
            return p.radio, max(p.budget.delays_s.values(), default=0.0)

        return replace(plan, proposals=tuple(propose(model, replan)))


@contextmanager
def gc_paused() -> Iterator[None]:
    """The cyclic garbage collector off for a block that allocates many small
    objects without cycles (a plan of 25,000 subscriptions: its passes over
    the model's dictionaries cost more than the planning). Reference
    counting still frees everything; the collector's previous state is
    restored. At the end, the objects allocated meanwhile (and any other
    young ones) join the oldest generation in O(1) (``freeze`` then
    ``unfreeze``) instead of being scanned by the next young collection
    (0.05-0.17 s for a plan's JSON of 25,000 streams; they are acyclic and
    freed by reference counting); skipped when the process has frozen
    objects of its own, which ``unfreeze`` would release."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            if gc.get_freeze_count() == 0:
                gc.freeze()
                gc.unfreeze()
            gc.enable()


@dataclass(frozen=True)
class _Options:
    """make_plan's options, the same for the plan and each proposal's."""

    ping_s: Fraction | None
    alpha: Fraction | None
    beta: Fraction | None
    max_buffer: int | None
    method: str
    calibration: Calibration | None
    status_period_s: int | None = None
    status_horizon_s: int | None = None


def _make_plan(model: Mapping[str, Any], options: _Options) -> Plan:
    o = options
    constants = constants_for(
        model, ping_s=o.ping_s, alpha=o.alpha, beta=o.beta, max_buffer=o.max_buffer
    )
    method, calibration = o.method, o.calibration
    tops = topics(dict(model))
    index = {name: i for i, name in enumerate(tops)}
    requested, subscriptions = asked_streams(model)
    for key, _ in requested:
        if key.topic not in index:
            index[key.topic] = len(index)

    published = {
        t.name: (t.type, t.period.numerator, t.period.denominator)
        for t in tops.values()
        if t.period is not None
    }

    def pricing(topic_name: str) -> Price:  # value bytes per second of a stream
        topic = published.get(topic_name)
        if topic is None:
            return lambda aggregation, p_num, p_den: float(
                _window_bytes(StreamKey(topic_name, aggregation, Fraction(p_num, p_den)), tops)
                / Fraction(p_num, p_den)
            )
        topic_type, pm_num, pm_den = topic
        return lambda aggregation, p_num, p_den: _cost(
            aggregation, topic_type, p_num, p_den, pm_num, pm_den
        )

    streams = plan_streams(requested, index, pricing)
    sent = sorted((s for s in streams if s.id is not None), key=lambda s: s.id or 0)
    hyper = _hyperperiod_us(model, [key for key, _ in requested])
    sched = Schedule.from_periods_us([_key_us(s.stream) for s in sent], hyper)
    try:
        sched.check_bounds()
    except ScheduleTooLarge as exc:
        raise PlanningError(_schedule_diagnostics(model, streams, exc)) from exc
    problem, unpublished = buffer_problem(model, tops, constants)
    try:
        buffers = _solve_buffers(problem, method)
    except BufferTooLarge as exc:
        position = {sub["name"]: i for i, sub in enumerate(model.get("subscribers", []))}
        raise PlanningError(
            [
                Diagnostic(
                    f"subscriber {name!r}: the planner cannot size the buffer of {exc}",
                    f"/subscribers/{position[name]}/periodS",
                )
                for name in exc.subscribers[:_MAX_NAMED]
            ]
        ) from exc

    def window(stream: StreamKey) -> Fraction:  # _window_bytes, from the topic's integers
        topic = published.get(stream.topic)
        if topic is None:
            return _window_bytes(stream, tops)
        pn, pd = stream._nd  # type: ignore[attr-defined]
        return _bytes(stream.aggregation, topic[0], pn * topic[2], pd * topic[1], _us_of(pn, pd))

    exact = [window(s.stream) for s in sent]
    link = LinkSettings.of(model)
    window_bytes, bound = quantised_window_bytes(
        model, sent, streams, exact, tops, link.transport, link.accepted_delay, False, calibration
    )
    use = calibration_use(model, sent, streams, tops, calibration) if calibration else None
    if use is not None and not (use.sizes or use.missing):
        use = None  # nothing quantised: nothing to calibrate
    calibrated = use is not None and bool(use.sizes)
    period, horizon = o.status_period_s, o.status_horizon_s
    budget = _budget(model, sched, sent, streams, window_bytes, calibrated, period, horizon)
    radio = model.get("link", {}).get("radio")
    ceiling = None
    if radio and bound is False:  # an estimate: the duty-cycle limit is checked on a bound
        ceiling_bytes, bounded = quantised_window_bytes(
            model, sent, streams, exact, tops, link.transport, link.accepted_delay, True
        )
        if bounded:
            ceiling = _budget(model, sched, sent, streams, ceiling_bytes, False, period, horizon)
    report = radio_report(RadioProfile.of(radio), budget, bound, ceiling, use) if radio else None
    return Plan(
        topics=tuple(tops.values()),
        streams=streams,
        subscriptions=subscriptions,
        schedule=sched,
        buffers=buffers,
        unpublished=unpublished,
        constants=constants,
        link=_link_cost(model, sched, window_bytes, tops),
        budget=budget,
        radio=report,
    )


def _hyperperiod_us(model: Mapping[str, Any], requested: Sequence[StreamKey]) -> int:
    """LCM of every requested period (µs), within :data:`HYPERPERIOD_BITS_LIMIT`."""
    hyper = 1 if requested else 0
    for us in dict.fromkeys(_key_us(key) for key in requested):  # distinct, in order
        hyper = lcm(hyper, us)
        if hyper.bit_length() > HYPERPERIOD_BITS_LIMIT:
            culprits = {_us(k.period) for k in requested if hyper % _us(k.period) == 0}
            subs = [
                (i, sub)
                for i, sub in enumerate(model.get("subscribers", []))
                if _us(period_of(sub["periodS"])) in culprits
            ][:20]
            raise PlanningError(
                [
                    Diagnostic(
                        f"subscriber {sub['name']!r}: the hyperperiod (the least common multiple "
                        f"of the subscription periods) exceeds 2^{HYPERPERIOD_BITS_LIMIT} µs; "
                        "choose periods that are multiples of one another",
                        f"/subscribers/{i}/periodS",
                    )
                    for i, sub in subs
                ]
            )
    return hyper


#: Diagnostics of a schedule the planner cannot count: one per period at most.
_MAX_NAMED = 5


def _schedule_diagnostics(
    model: Mapping[str, Any], streams: Sequence[PlannedStream], exc: ScheduleTooLarge
) -> list[Diagnostic]:
    """One located error per offending sent period: at its first subscriber,
    naming the others (a derived stream's subscribers count for its source)."""
    culprits = set(exc.periods_us)
    by_period: dict[int, list[str]] = {}
    for s in streams:
        periods = [_us(s.stream.period)] if s.sent else [_us(x.stream.period) for x in s.sources]
        for p in periods:
            if p in culprits:
                by_period.setdefault(p, []).extend(s.subscribers)
    position = {sub["name"]: i for i, sub in enumerate(model.get("subscribers", []))}
    out: list[Diagnostic] = []
    for p in sorted(by_period):
        names = sorted(set(by_period[p]), key=lambda n: position.get(n, 0))
        if not names:
            continue  # a helper stream nobody asked for: named with its topic's others
        others = names[1:_MAX_NAMED]
        more = len(names) - 1 - len(others)
        also = (
            f" (also {', '.join(others)}" + (f" and {more} more" if more else "") + ")"
            if others
            else ""
        )
        out.append(
            Diagnostic(
                f"subscriber {names[0]!r}{also}: sent every {_seconds(p)} s; the planner cannot "
                f"schedule {exc}",
                f"/subscribers/{position.get(names[0], 0)}/periodS",
            )
        )
    return out or [Diagnostic(f"the planner cannot schedule {exc}", "/subscribers")]
