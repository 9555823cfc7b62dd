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

from modd_contracts import events, labels
from modd_model.numbers import MICROS_PER_SECOND
from modd_model.query import link_settings
from modd_plan import Plan, make_plan
from modd_plan.linkbudget import LinkSettings
from modd_plan.resolution import stream_resolutions
from modd_plan.streams import StreamKey

from modd.link.frames import (
    MAX_ACCEPTED_DELAY_MS,
    Aggregation,
    Config,
    StreamSpec,
    TopicSpec,
    ValueType,
)

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
        raise OverBudget(
            "a model given up for its planning budget is still being planned; retry in a moment"
        )
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
        raise OverBudget(
            f"planning this model takes longer than the SubBroker's budget of "
            f"{budget_s:g} s ([link] plan_budget_s)"
        )
    try:
        return future.result()
    except MemoryError as exc:
        raise OverBudget("planning this model ran out of memory") from exc


def accepted_delay_ms(
    model: dict[str, Any], configured: dict[str, Any], transport: str
) -> int | None:
    """The CONFIG's optional accepted delay (docs/protocol.md, "CONFIG"): on a
    datagram link, the ``model``'s ``Link.delay`` in ms when it differs from the
    ``configured`` model's (the one the PubBroker's config file was generated
    from, ``link.delay_ms``), else None: a CONFIG that changes nothing stays byte
    for byte the one an older PubBroker reads. ValueError above one hour.

    >>> accepted_delay_ms({"link": {"acceptedDelayS": "0.25"}}, {}, "udp")
    250
    >>> accepted_delay_ms({"link": {"acceptedDelayS": "1"}}, {}, "udp") is None
    True
    >>> accepted_delay_ms({"link": {"acceptedDelayS": "0.25"}}, {}, "tcp") is None
    True
    """
    if transport == "tcp":
        return None
    ms = int(LinkSettings.of(model, transport).accepted_delay * 1000)
    if ms == int(LinkSettings.of(configured, transport).accepted_delay * 1000):
        return None
    if ms > MAX_ACCEPTED_DELAY_MS:
        raise ValueError(f"the link's accepted delay ({ms / 1000:g} s) is above one hour")
    return ms


def config_for(
    plan: Plan,
    config_id: int,
    status_period_s: int = 60,
    accepted_delay_ms: int | None = None,
    resolutions: tuple[float | None, ...] | None = None,
) -> Config:
    """The CONFIG frame of a plan. Topics nobody publishes get buffer size 1;
    ``accepted_delay_ms`` and ``resolutions`` (one per sent stream, see
    :func:`resolutions_of`) are the optional trailing fields."""
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
    streams = tuple(_stream_spec(index[s.stream.topic], s.stream) for s in plan.sent_streams)
    return Config(config_id, status_period_s, topics, streams, accepted_delay_ms, resolutions)


def _stream_spec(topic: int, stream: StreamKey) -> StreamSpec:
    """A sent stream as CONFIG names it: PERCENTILE(p)'s label is its code and p,
    an event stream's its code, parameters and N."""
    name, p = labels.parse(stream.aggregation)
    event = events.parse_label(stream.aggregation) if labels.is_event(stream.aggregation) else None
    return StreamSpec(topic, Aggregation[name], period_us(stream), p, event)


def resolutions_of(model: dict[str, Any], plan: Plan) -> tuple[float | None, ...] | None:
    """The sent streams' declared resolutions, None when no stream has one (the
    CONFIG then stays byte for byte the one an older PubBroker reads)."""
    found = stream_resolutions(model, plan.sent_streams, plan.streams)
    return tuple(found) if any(r is not None for r in found) else None


def trailing_fields(
    model: dict[str, Any], configured: dict[str, Any], transport: str, plan: Plan
) -> tuple[int | None, tuple[float | None, ...] | None]:
    """The CONFIG's optional accepted delay and resolutions: the resolution field
    follows the delay, so a plan with resolutions carries the model's delay too."""
    delay = accepted_delay_ms(model, configured, transport)
    resolutions = resolutions_of(model, plan)
    if resolutions is not None and delay is None:
        delay = min(int(LinkSettings.of(model).accepted_delay * 1000), MAX_ACCEPTED_DELAY_MS)
    return delay, resolutions
