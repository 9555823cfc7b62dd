"""Builds a CONFIG from the planner's plan JSON (the shared plan/link contract).

`plan["topics"]` gives ids, names, types and buffer sizes; `plan["streams"]` the streams
(topic by name or id), those with `sent` true and an integer `id` going on the wire in id
order.

Example::

    config = config_from_plan(plan.to_json(), config_id=1, status_period_s=30)
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from modd.link.frames import Aggregation, Config, StreamSpec, TopicSpec, ValueType


def config_from_plan(plan: Mapping[str, Any], config_id: int, status_period_s: int = 30) -> Config:
    if not 1 <= config_id <= 255:
        raise ValueError("config_id must be 1..255")
    topics_json = sorted(plan["topics"], key=lambda t: t["id"])
    for i, t in enumerate(topics_json):
        if t["id"] != i:
            raise ValueError(f"/topics/{i}/id: expected {i}, got {t['id']}")
    topics = tuple(
        TopicSpec(
            t["name"], ValueType.parse(t.get("type", "float32")), int(t["buffer_size"]),
            int(t.get("period_us") or 0),
        )
        for t in topics_json
    )
    sent = sorted((s for s in plan["streams"] if s.get("sent") and s.get("id") is not None),
                  key=lambda s: s["id"])
    topic_ids = {t.name: i for i, t in enumerate(topics)}
    streams = []
    for i, s in enumerate(sent):
        if s["id"] != i:
            raise ValueError(f"stream ids must be 0..k-1, found {s['id']} at position {i}")
        agg = Aggregation[s["aggregation"]]
        topic = s["topic"]  # the topic's name (plan JSON) or its id
        tid = topic_ids[topic] if isinstance(topic, str) else int(topic)
        streams.append(StreamSpec(tid, agg, int(s["period_us"])))
    return Config(config_id, status_period_s, topics, tuple(streams))
