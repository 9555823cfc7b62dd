"""The deployment the SubBroker is running: the config the PubBroker
acknowledged, its plan and the fan-out that delivers it. Read by the broker,
the backfill manager and the backfill queryable (its own module so that they
need not import the broker that composes them)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from modd_plan import Plan
from modd_plan.streams import Source, StreamKey

from modd.link.frames import Config

from .delivery import SlotDelivery
from .fanout import FanOut
from .kept import Deployment


@dataclass
class Running:
    """A config the PubBroker acknowledged, with everything to fan it out."""

    model: dict[str, Any]
    plan: Plan
    config: Config
    epoch_ns: int
    fanout: FanOut
    meta: Deployment = field(default_factory=Deployment.configured)
    topic_info: dict[str, tuple[str, str]] = field(default_factory=dict)  # unit, type
    slots: SlotDelivery | None = None
    rtt_s: float | None = None  # the round trip its plan was made for (handover.py)
    last_slot: int = 0  # the latest slot whose windows came (handover.py)

    def route(self, stream: StreamKey, sources: tuple[Source, ...], subscriber: str) -> None:
        self.fanout.route(stream, sources, subscriber)

    def unroute(self, subscriber: str) -> bool:
        return self.fanout.unroute(subscriber)
