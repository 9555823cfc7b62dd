"""Fixtures of the planner tests: model dicts built directly (no parser)."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import pytest

Model = dict[str, Any]

SCENARIO1_SUBS = [
    ("sub_1", "accel_x", "2.0", "AVERAGE"),
    ("sub_2", "accel_y", "2.0", "AVERAGE"),
    ("sub_3", "accel_x", "0.25", "AVERAGE"),
    ("sub_4", "accel_y", "0.25", "AVERAGE"),
    ("sub_5", "accel_z", "0.25", "MIN"),
    ("sub_6", "accel_z", "0.25", "MAX"),
    ("sub_7", "accel_z", "0.25", "MAX"),
]


def build_model(
    variables: Sequence[str | tuple[str, str]],
    publishers: Sequence[tuple[str, str, Sequence[str]]],
    subscribers: Sequence[tuple[str, str, str, str]],
    *,
    sensor: str = "s",
    link: dict[str, Any] | None = None,
) -> Model:
    """A valid model of drone ``d`` with one sensor; topics are ``d.<sensor>.<var>``.

    ``variables``: names, or (name, type); ``publishers``: (name, period,
    [variables]); ``subscribers``: (name, variable, period, aggregation)."""
    prefix = f"d.{sensor}."
    vars_json = [
        {"name": v, "unit": "NONE"}
        if isinstance(v, str)
        else {"name": v[0], "unit": "NONE", "type": v[1]}
        for v in variables
    ]
    model: Model = {
        "schemaVersion": "1.0",
        "drone": {"name": "d", "sensors": [{"name": sensor, "variables": vars_json}]},
        "pubBroker": {"endpoint": {"host": "127.0.0.1", "port": 7171}, "logPath": "/tmp/x"},
        "subBroker": {"endpoint": {"host": "127.0.0.1", "port": 7272}, "configPath": "/tmp/y"},
        "publishers": [
            {"name": n, "periodS": p, "topics": [prefix + t for t in ts]} for n, p, ts in publishers
        ],
        "subscribers": [
            {"name": n, "topic": prefix + t, "periodS": p, "aggregation": a}
            for n, t, p, a in subscribers
        ],
    }
    if link is not None:
        model["link"] = link
    return model


@pytest.fixture
def make_model() -> Any:
    """The model builder (see :func:`build_model`)."""
    return build_model


@pytest.fixture
def scenario1_dict() -> Model:
    """Scenario 1 of the paper as a dict (topics d.accelerometer.accel_*)."""
    axes = ["accel_x", "accel_y", "accel_z"]
    return build_model(axes, [("pub_1", "0.04", axes)], SCENARIO1_SUBS, sensor="accelerometer")
