"""Read-only views of a model that every consumer needs (planner, generators,
runtime): topics with their publication period, link constants with defaults.

A model is the JSON document the schema describes (a ``dict``); these helpers
assume it has passed validation (``modd_model.validate``)."""

from __future__ import annotations

from dataclasses import dataclass
from fractions import Fraction
from typing import Any

from .numbers import to_fraction

Model = dict[str, Any]

#: Planner constants of the paper (MAX_BUFFER, PING_TIME, alpha, beta).
DEFAULT_MAX_BUFFER = 1000
DEFAULT_PING_S = "0.83"
DEFAULT_ALPHA = "1"
DEFAULT_BETA = "1"
DEFAULT_VALUE_TYPE = "float32"


@dataclass(frozen=True, init=False)
class Topic:
    """A measured variable seen as a topic."""

    name: str  # fully qualified: drone.sensor.variable
    sensor: str
    variable: str
    unit: str
    type: str  # float32 | float64 | int | bool
    publisher: str | None  # name of the publisher that publishes it, if any
    period: Fraction | None  # publication period in seconds, if published

    def __init__(
        self,
        name: str,
        sensor: str,
        variable: str,
        unit: str,
        type: str,  # noqa: A002
        publisher: str | None,
        period: Fraction | None,
    ) -> None:
        # one dictionary update, not a frozen dataclass's setattr per field
        # (a plan of 5,000 topics builds 5,000)
        self.__dict__.update(
            name=name,
            sensor=sensor,
            variable=variable,
            unit=unit,
            type=type,
            publisher=publisher,
            period=period,
        )


@dataclass(frozen=True)
class LinkSettings:
    """Link constants with the paper's defaults filled in."""

    transport: str
    key_ref: str | None
    expected_rtt_s: Fraction | None
    max_buffer: int
    ping_s: Fraction
    alpha: Fraction
    beta: Fraction


def topic_name(drone: str, sensor: str, variable: str) -> str:
    return f"{drone}.{sensor}.{variable}"


def topics(model: Model) -> dict[str, Topic]:
    """Every topic of the model by fully qualified name, in declaration order."""
    published: dict[str, tuple[str, Fraction]] = {}
    for pub in model.get("publishers", []):
        entry = (pub["name"], to_fraction(pub["periodS"]))  # once per publisher
        for t in pub["topics"]:
            published.setdefault(t, entry)
    drone = model["drone"]["name"]
    out: dict[str, Topic] = {}
    for sensor in model["drone"]["sensors"]:
        for var in sensor["variables"]:
            name = topic_name(drone, sensor["name"], var["name"])
            pub_name, period = published.get(name, (None, None))
            out[name] = Topic(
                name=name,
                sensor=sensor["name"],
                variable=var["name"],
                unit=var["unit"],
                type=var.get("type", DEFAULT_VALUE_TYPE),
                publisher=pub_name,
                period=period,
            )
    return out


def link_settings(model: Model) -> LinkSettings:
    link = model.get("link", {})
    rtt = link.get("expectedRttS")
    return LinkSettings(
        transport=link.get("transport", "tcp"),
        key_ref=link.get("keyRef"),
        expected_rtt_s=to_fraction(rtt) if rtt is not None else None,
        max_buffer=int(link.get("maxBuffer", DEFAULT_MAX_BUFFER)),
        ping_s=to_fraction(link.get("pingS", DEFAULT_PING_S)),
        alpha=to_fraction(link.get("alpha", DEFAULT_ALPHA)),
        beta=to_fraction(link.get("beta", DEFAULT_BETA)),
    )
