"""The paper's scenarios as loads: publishers (period, topics), subscriptions (name, topic,
period, aggregation), the planner's prediction, the information floor and the paper's
figures (metamodel/examples/scenarios/expected.json)."""

from __future__ import annotations

import json
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

from modd_model import load_model
from modd_plan import make_plan
from subbroker_harness import SCENARIOS

TCP_SEGMENT_HEADERS = 52  # IPv4 20 + TCP 20 + timestamps option 12
VALUE_BYTES = 4  # a float32 value


@dataclass(frozen=True)
class Subscription:
    name: str
    topic: str
    period_s: Fraction
    aggregation: str


@dataclass(frozen=True)
class Scenario:
    number: int
    path: Path
    drone: str
    publishers: list[tuple[Fraction, list[str]]]
    subscriptions: list[Subscription]
    planned_down: float  # planner: drone -> base B/s, IP+TCP headers included
    planned_up: float
    sent_values_per_s: float  # values of the streams the plan sends (nothing derivable)
    slots_per_s: float
    paper: dict[str, Any]

    @property
    def floor_down(self) -> float:
        """Information floor: each needed value as 4 B, one TCP segment per slot."""
        return self.sent_values_per_s * VALUE_BYTES + self.slots_per_s * TCP_SEGMENT_HEADERS

    @property
    def paper_modd_down(self) -> float:
        return float(self.paper["paper_bytes_per_s"]["drone_to_base_modd"])

    @property
    def samples_per_s(self) -> float:
        return float(sum(len(ts) / p for p, ts in self.publishers))


def load(number: int) -> Scenario:
    path = SCENARIOS / f"scenario{number}.modd"
    model = load_model(path)
    plan = make_plan(model)
    link = plan.link
    sched = plan.schedule
    expected = json.loads((SCENARIOS / "expected.json").read_text())
    return Scenario(
        number=number,
        path=path,
        drone=model["drone"]["name"],
        publishers=[(Fraction(p["periodS"]), list(p["topics"])) for p in model["publishers"]],
        subscriptions=[
            Subscription(s["name"], s["topic"], Fraction(s["periodS"]), s["aggregation"])
            for s in model["subscribers"]
        ],
        planned_down=float(link.drone_to_base),
        planned_up=float(link.base_to_drone),
        sent_values_per_s=float(sum(1 / s.stream.period for s in plan.sent_streams)),
        slots_per_s=float(sched.messages_per_hyperperiod / sched.hyperperiod),
        paper=expected[f"scenario{number}"],
    )
