"""What every target needs from a model, computed once: the topics with their
types, the publishers with their topics, the plan (buffer sizes), the ingress."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from modd_model.ingress import Ingress, ingress_of
from modd_model.query import Topic, link_settings, topics
from modd_plan import Plan, make_plan


@dataclass
class PublisherView:
    name: str
    period_s: str
    topics: list[Topic]


@dataclass(frozen=True)
class Station:
    """Where the subscribers of a running deployment connect: the SubBroker's
    zenoh endpoint, and the path of a viewer's credentials file there (a path
    given at run time, never the password)."""

    zenoh_connect: str
    viewer_credentials: str | None = None


@dataclass
class Context:
    model: dict[str, Any]
    drone: str
    topics: dict[str, Topic]
    publishers: list[PublisherView]
    plan: Plan
    ingress: Ingress
    key_ref: str
    extra: dict[str, Any] = field(default_factory=dict)
    station: Station | None = None


DEFAULT_KEY_REF = "env:MODD_LINK_KEY"


def build_context(model: dict[str, Any]) -> Context:
    tops = topics(model)
    pubs = [
        PublisherView(p["name"], p["periodS"], [tops[t] for t in p["topics"]])
        for p in model["publishers"]
    ]
    return Context(
        model=model,
        drone=model["drone"]["name"],
        topics=tops,
        publishers=pubs,
        plan=make_plan(model),
        ingress=ingress_of(model),
        key_ref=link_settings(model).key_ref or DEFAULT_KEY_REF,
    )
