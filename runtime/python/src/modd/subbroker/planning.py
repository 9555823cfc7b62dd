"""Planning at run time: the plan of a model with the measured RTT, and the
CONFIG frame that tells the PubBroker to execute it (the plan/link contract
of docs/protocol.md: topics in declaration order, the sent streams in
stream-id order, periods in whole microseconds).

>>> config = config_for(plan_for(model, rtt_s=0.002), config_id=1)    # doctest: +SKIP
"""

from __future__ import annotations

import threading
from concurrent.futures import Future
from fractions import Fraction
from typing import Any

from modd_model.numbers import MICROS_PER_SECOND
from modd_model.query import link_settings
from modd_plan import Plan, make_plan

from modd.link.frames import Aggregation, Config, StreamSpec, TopicSpec, ValueType

from .fanout import period_us


def plan_for(model: dict[str, Any], rtt_s: float | None) -> Plan:
    """The plan with PING_TIME = max(the model's pingS, the measured RTT): a
    slow link loosens the delay cap; a fast one never tightens it below the
    model's (3 x 0.1 ms would make every loopback plan infeasible)."""
    ping = link_settings(model).ping_s
    if rtt_s is not None:
        ping = max(ping, Fraction(str(round(rtt_s, 6))))
    return make_plan(model, ping_s=ping)


class OverBudget(ValueError):
    """A model the SubBroker cannot plan within its budget."""


_running_over: list[threading.Thread] = []


def plan_within(model: dict[str, Any], rtt_s: float | None, budget_s: float) -> Plan:
    """:func:`plan_for` on a worker thread, given up after ``budget_s``
    (OverBudget; ValueError for a model that cannot be planned at all). The
    planner's memory is bounded (modd_plan.buffers.CANDIDATE_LIMIT) but not its
    time on a pathological model: a plan given up goes on computing on its
    thread, so while one still runs every other request is refused at once."""
    _running_over[:] = [t for t in _running_over if t.is_alive()]
    if _running_over:
        raise OverBudget("a model given up for its planning budget is still being planned; "
                         "retry in a moment")
    future: Future[Plan] = Future()

    def work() -> None:
        try:
            future.set_result(plan_for(model, rtt_s))
        except BaseException as exc:  # handed to the caller
            future.set_exception(exc)

    thread = threading.Thread(target=work, name="modd-plan", daemon=True)
    thread.start()
    thread.join(budget_s)
    if thread.is_alive():
        _running_over.append(thread)
        raise OverBudget(f"planning this model takes longer than the SubBroker's budget of "
                         f"{budget_s:g} s ([link] plan_budget_s)")
    try:
        return future.result()
    except MemoryError as exc:
        raise OverBudget("planning this model ran out of memory") from exc


def config_for(plan: Plan, config_id: int, status_period_s: int = 60) -> Config:
    """The CONFIG frame of a plan. Topics nobody publishes get buffer size 1."""
    if not 1 <= config_id <= 255:
        raise ValueError("config_id must be 1..255")
    sizes = plan.buffer_sizes
    index = {t.name: i for i, t in enumerate(plan.topics)}
    topics = tuple(
        TopicSpec(
            t.name,
            ValueType.parse(t.type),
            int(sizes.get(t.name, 1)),
            int(t.period * MICROS_PER_SECOND) if t.period is not None else 0,
        )
        for t in plan.topics
    )
    streams = tuple(
        StreamSpec(index[s.stream.topic], Aggregation[s.stream.aggregation], period_us(s.stream))
        for s in plan.sent_streams
    )
    return Config(config_id, status_period_s, topics, streams)
