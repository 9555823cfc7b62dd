"""The plan as one JSON object: the shape the backend, the UI, the CLI
(``modd plan FILE --json``) and the SubBroker's CONFIG builder read.

Periods and delays are decimal strings (exact); wire periods are integer
microseconds. See docs/planning.md for every field.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from fractions import Fraction
from functools import lru_cache
from operator import itemgetter
from typing import Any, Protocol

from modd_contracts import labels
from modd_contracts.types_gen import (
    PlanDocument,
    PlanRadio,
    PlanRadioDiagnostic,
    PlanSchedule,
    PlanSentStream,
    PlanStream,
)
from modd_model.numbers import MICROS_PER_SECOND
from modd_model.query import Topic

from .buffers import BufferSolution, Infeasibility
from .linkbudget import LinkBudget
from .linkcost import LinkCost, event_window_bytes, events_at_most
from .proposals import Proposal
from .radio import RadioReport
from .schedule import Schedule, Slot
from .streams import PlannedStream, StreamKey, _decimal_of, decimal_of


class _Constants(Protocol):
    def to_json(self) -> dict[str, Any]: ...


class PlanView(Protocol):
    """What the JSON reads of a plan: ``plan.Plan`` is one. A protocol, not an
    import of ``Plan``, so that ``plan.py`` (which renders itself through this
    module) and this module do not import each other."""

    @property
    def topics(self) -> tuple[Topic, ...]: ...
    @property
    def streams(self) -> tuple[PlannedStream, ...]: ...
    @property
    def subscriptions(self) -> dict[str, StreamKey]: ...
    @property
    def schedule(self) -> Schedule: ...
    @property
    def buffers(self) -> BufferSolution: ...
    @property
    def constants(self) -> _Constants: ...
    @property
    def link(self) -> LinkCost: ...
    @property
    def budget(self) -> LinkBudget | None: ...
    @property
    def sent_streams(self) -> list[PlannedStream]: ...
    @property
    def buffer_sizes(self) -> dict[str, int]: ...
    @property
    def infeasible(self) -> tuple[Infeasibility, ...]: ...
    @property
    def radio(self) -> RadioReport | None: ...
    @property
    def proposals(self) -> tuple[Proposal, ...]: ...


#: Slots listed in the JSON schedule (the first hyperperiod when it is
#: shorter), and at most this many stream ids over the listed slots, so that
#: a plan of 10,000 subscriptions stays a small document.
SLOT_LIST_LIMIT = 1000
SLOT_ENTRY_LIMIT = 20_000


def _dec(value: Fraction) -> str:
    return decimal_of(value)


def _us(value: Fraction) -> int:
    return _us_of(value.numerator, value.denominator)


@lru_cache(maxsize=65_536)  # keyed by integers: a plan repeats few publication periods
def _us_of(numerator: int, denominator: int) -> int:
    return int(Fraction(numerator, denominator) * MICROS_PER_SECOND)


def _key_us(key: StreamKey) -> int:
    num, den = key._nd  # type: ignore[attr-defined]
    return int(num * MICROS_PER_SECOND // den)


@lru_cache(maxsize=65_536)  # bounded: a plan repeats few delays
def _dec_us(us: int) -> str:
    return decimal_of(Fraction(us, MICROS_PER_SECOND))


def _streams_json(
    streams: Sequence[PlannedStream],
) -> tuple[list[PlanStream], list[PlanSentStream]]:
    """The streams' JSON objects, and the schedule's (the sent streams by
    id). A plan repeats few periods: their decimal and microsecond forms are
    computed once per period, not per stream."""
    periods: dict[tuple[int, int], tuple[str, int]] = {}
    out: list[PlanStream] = []
    append = out.append
    sent: list[PlanSentStream] = []
    for s in streams:
        key = s.stream
        nd = key._nd  # type: ignore[attr-defined]
        period = periods.get(nd)
        if period is None:
            period = periods[nd] = (_decimal_of(*nd), _key_us(key))
        sources = s.sources
        first = sources[0] if sources else None
        if s.id is not None:
            sent.append({"id": s.id, "key": key.key, "period_us": period[1]})
        append(
            {
                "id": s.id,
                "key": key.key,
                "topic": key.topic,
                "aggregation": key.aggregation,
                "period_s": period[0],
                "period_us": period[1],
                "sent": s.id is not None,
                "derived_from": first.stream.key if first else None,
                "factor": first.factor if first else 1,
                "sources": (
                    [{"key": x.stream.key, "factor": x.factor} for x in sources] if sources else []
                ),  # a sent stream's: no comprehension to run
                "subscribers": list(s.subscribers),
            }
        )
    sent.sort(key=itemgetter("id"))  # in order already from plan_streams: one linear pass
    return out, sent


def _schedule_json(plan: PlanView, streams: list[PlanSentStream]) -> PlanSchedule:
    sched = plan.schedule
    slots: list[Slot] = []
    entries = 0
    limit = min(SLOT_LIST_LIMIT, sched.messages_per_hyperperiod)
    for slot in itertools.islice(sched.iter_slots(), limit):
        entries += len(slot[2])
        if entries > SLOT_ENTRY_LIMIT and slots:
            break
        slots.append(slot)
    return {
        "epoch_phase_s": "0.0",
        "streams": streams,
        "slots": [{"slot": k, "date_s": _dec(date), "streams": ids} for k, date, ids in slots],
        "slots_listed": len(slots),
        "slots_truncated": sched.messages_per_hyperperiod > len(slots),
    }


def _event_bounds(plan: PlanView, streams: list[PlanStream]) -> None:
    """An event stream's worst case (docs/planning.md, "Event subscriptions"): its
    events a window and its value bytes a second, at most (the plan counts it so)."""
    periods = {t.name: (t.type, t.period) for t in plan.topics if t.period is not None}
    for s in streams:
        if not labels.is_event(s["aggregation"]) or not s["sent"]:
            continue
        vtype, pm = periods.get(s["topic"], ("float32", None))
        samples = Fraction(s["period_us"], MICROS_PER_SECOND) / pm if pm else Fraction(0)
        window = event_window_bytes(s["aggregation"], vtype, samples, s["period_us"])
        s["events_at_most"] = events_at_most(s["aggregation"], samples)
        s["bytes_per_s_at_most"] = round(window * MICROS_PER_SECOND / s["period_us"], 3)


def plan_to_json(plan: PlanView) -> PlanDocument:
    """Every field of the shared contract (docs/planning.md, "Plan JSON")."""
    sizes = plan.buffer_sizes
    streams, sent = _streams_json(plan.streams)
    _event_bounds(plan, streams)
    doc: PlanDocument = {
        "hyperperiod_s": _dec(plan.schedule.hyperperiod),
        "messages_per_hyperperiod": plan.schedule.messages_per_hyperperiod,
        "topics": [
            {
                "id": i,
                "name": t.name,
                "type": t.type,
                "unit": t.unit,
                "publication_period_s": _dec(t.period) if t.period is not None else None,
                "period_us": _us(t.period) if t.period is not None else None,
                "buffer_size": sizes.get(t.name),
            }
            for i, t in enumerate(plan.topics)
        ],
        "streams": streams,
        "subscriptions": {name: key.key for name, key in plan.subscriptions.items()},
        "buffer_sizes": sizes,
        "schedule": _schedule_json(plan, sent),
        "delays": {name: _dec_us(us) for name, us in plan.buffers.deviations_us.items()},
        "max_delay_s": _dec(Fraction(plan.buffers.max_deviation_us, MICROS_PER_SECOND)),
        "predicted_link_bytes_per_s": plan.link.to_json(),
        "link_budget": plan.budget.to_json() if plan.budget is not None else None,
        "infeasible": [
            {"topic": x.topic, "subscribers": list(x.subscribers), "reason": x.reason}
            for x in plan.infeasible
        ],
        "violates_delay_cap": bool(plan.buffers.infeasible),
        "constants": plan.constants.to_json(),
    }
    if plan.radio is not None:  # absent without link.radio: such plans' JSON is unchanged
        doc["radio"] = _radio_json(plan, plan.radio)
    return doc


def _radio_json(plan: PlanView, radio: RadioReport) -> PlanRadio:
    """The radio's report, its refusal located (the duty-cycle limit and the
    subscriptions that cost most, by their place in the model) and the
    proposals that fit."""
    out = radio.to_json()
    if radio.error is not None:
        position = {name: i for i, name in enumerate(plan.subscriptions)}
        located: list[PlanRadioDiagnostic] = [{"pointer": "/link/radio", "message": radio.error}]
        out["diagnostics"] = located + [
            {
                "pointer": f"/subscribers/{position[c.name]}",
                "message": f"{c.name} costs {c.air_s_per_hour:.1f} s of air time per hour "
                f"({c.bytes_per_s:.1f} B/s)",
            }
            for c in radio.costs[:5]
            if c.name in position
        ]
    out["proposals"] = [p.to_json() for p in plan.proposals]
    return out
