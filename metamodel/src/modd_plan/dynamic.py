"""Dynamic subscriptions (paper §III-B2): a subscriber asks, while the
mission runs, for (topic, period, aggregation). The schedule does not change;
the request is accepted only when the SubBroker can compute it from the
streams already sent.

>>> check_dynamic(plan, "usv.accelerometer.accel_x", "4", "AVERAGE")   # doctest: +SKIP
Accepted(stream='usv.accelerometer.accel_x/AVERAGE/4.0', sources=(...), factor=16)
"""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction

from modd_contracts import aggregations_gen as agg
from modd_contracts import labels
from modd_model.numbers import fraction_to_decimal, to_fraction

from .derive import PAIR_SOURCE_RULES, SINGLE_SOURCE_RULES
from .plan import Plan
from .streams import AGGREGATIONS, Source, StreamKey, find_sources


@dataclass(frozen=True)
class Accepted:
    """The request can be served: ``stream`` is its key, computed from
    ``sources`` (sent streams; ``factor`` windows of the first one)."""

    stream: str
    sources: tuple[Source, ...]

    @property
    def derived_from(self) -> str:
        return self.sources[0].stream.key

    @property
    def factor(self) -> int:
        return self.sources[0].factor


@dataclass(frozen=True)
class NotAvailable:
    """The request cannot be served without a new plan; ``reason`` says why."""

    reason: str


def _sec(period: Fraction) -> str:
    return fraction_to_decimal(period) + " s"


def _period(period_s: str | Fraction) -> Fraction | None:
    try:
        value = to_fraction(period_s) if isinstance(period_s, str) else period_s
    except ValueError:
        return None
    return value if value > 0 else None


def check_dynamic(
    plan: Plan, topic: str, period_s: str | Fraction, aggregation: str
) -> Accepted | NotAvailable:
    """Accept (topic, period, aggregation) if it is sent or derivable from
    what is sent; otherwise say why not, in the scientist's terms."""
    try:
        labels.parse(aggregation)  # PERCENTILE with its p: PERCENTILE(95)
    except ValueError:
        known = ", ".join(a if a != agg.PERCENTILE else "PERCENTILE(p)" for a in AGGREGATIONS)
        return NotAvailable(f"unknown aggregation {aggregation!r}; use one of {known}")
    if all(t.name != topic for t in plan.topics):
        return NotAvailable(f"the model has no topic named {topic!r}")
    period = _period(period_s)
    if period is None:
        return NotAvailable(f"the period {period_s!r} is not a positive decimal number of seconds")
    sent = [s.stream for s in plan.sent_streams if s.stream.topic == topic]
    target = StreamKey(topic, aggregation, period)
    sources = find_sources(target, sent)
    if sources is not None:
        return Accepted(target.key, sources)
    return NotAvailable(_why_not(target, sent))


def _why_not(target: StreamKey, sent: list[StreamKey]) -> str:
    if not sent:
        return f"nothing of {target.topic} is sent to the base station in the current plan"
    listing = ", ".join(f"{s.aggregation} every {_sec(s.period)}" for s in sent)
    dividing = [s for s in sent if (target.period / s.period).denominator == 1]
    if not dividing:
        return (
            f"{_sec(target.period)} is not a whole multiple of any period sent for "
            f"{target.topic} ({listing})"
        )
    usable = list(SINGLE_SOURCE_RULES[target.aggregation])
    pair = PAIR_SOURCE_RULES.get(target.aggregation)
    needs = " or ".join(usable) + (f" or both {' and '.join(pair)}" if pair else "")
    return (
        f"{target.aggregation} every {_sec(target.period)} needs {needs} at a period dividing "
        f"{_sec(target.period)}, but {target.topic} is sent as {listing}"
    )
