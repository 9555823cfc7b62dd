"""A stream's aggregation *label*: the aggregation table's name, with its
parameter for the one that takes one, ``PERCENTILE(95)`` (docs/protocol.md).

The model writes PERCENTILE's p apart (``"aggregation": "PERCENTILE",
"percentile": 95``); the plan, CONFIG's reader and the delivered values name
the stream by its label, so that two percentiles of one topic and period are
two streams. p's text is the shortest that reads back to the same double.

>>> label("PERCENTILE", 95), label("MEDIAN"), parse("PERCENTILE(99.5)")
('PERCENTILE(95)', 'MEDIAN', ('PERCENTILE', 99.5))
>>> spec("PERCENTILE(5)").code, rank("PERCENTILE(5)") < rank("PERCENTILE(50)")
(11, True)
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypeVar

from . import events
from .aggregations_gen import BY_NAME, PERCENTILE, AggregationSpec

_V = TypeVar("_V")


def p_text(p: float) -> str:
    """``95.0`` -> ``"95"``, ``99.5`` -> ``"99.5"``."""
    return repr(float(p)).removesuffix(".0")


def is_event(text: str) -> bool:
    """Whether a label names an event subscription (ON_CHANGE, THRESHOLD)."""
    return base(text) in events.EVENT_AGGREGATIONS


def label(aggregation: str, p: float | None = None) -> str:
    """The stream's label: ``aggregation``, with ``(p)`` for PERCENTILE."""
    if aggregation != PERCENTILE:
        return aggregation
    if p is None:
        raise ValueError("PERCENTILE needs its p")
    return f"{PERCENTILE}({p_text(p)})"


def of_subscriber(sub: Mapping[str, Any]) -> str:
    """The label of a model's subscriber (its aggregation and percentile, or an
    event subscription's parameters, modd_contracts.events)."""
    if sub["aggregation"] in events.EVENT_AGGREGATIONS:
        return events.of_subscriber(sub).text()
    return label(sub["aggregation"], sub.get("percentile"))


def parse(text: str) -> tuple[str, float | None]:
    """A label's (aggregation, p); ValueError naming the text when it is none."""
    name, paren, rest = text.partition("(")
    if name in events.EVENT_AGGREGATIONS:
        events.parse_label(text)  # ValueError naming the text
        return name, None
    if name not in BY_NAME or (paren and name != PERCENTILE) or (name == PERCENTILE) != bool(paren):
        raise ValueError(f"unknown aggregation {text!r}")
    if not paren:
        return name, None
    try:
        p = float(rest.removesuffix(")")) if rest.endswith(")") else math.nan
    except ValueError:
        p = math.nan
    if not 0 <= p <= 100:
        raise ValueError(f"unknown aggregation {text!r} (p from 0 to 100)")
    return name, p


def base(text: str) -> str:
    """The aggregation table's name of a label."""
    return text.partition("(")[0]


def spec(text: str) -> AggregationSpec:
    """The aggregation table's row of a label."""
    return BY_NAME[base(text)]


def rank(text: str) -> float:
    """The stream-id order of a label: the wire code, then p."""
    name, p = parse(text) if "(" in text else (text, None)
    if name in events.EVENT_AGGREGATIONS:
        p = None  # event streams of one topic and period: in the model's order
    return BY_NAME[name].code * 1000 + (p or 0.0)


class ByLabel(dict[str, _V]):
    """A table keyed by aggregation name, read by label too: a label's
    missing key reads its aggregation's (``PERCENTILE(95)`` -> ``PERCENTILE``)."""

    def __missing__(self, key: str) -> _V:
        if "(" not in key:
            raise KeyError(key)
        return self[base(key)]


class RankByLabel(dict[str, float]):
    """The stream-id order of each label, :func:`rank`, computed once each."""

    def __missing__(self, key: str) -> float:
        self[key] = value = rank(key)
        return value
