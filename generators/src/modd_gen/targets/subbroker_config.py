"""The SubBroker's configuration (TOML, docs/subbroker.md) and the model it
serves, for the operator. The SubBroker plans at run time with the measured
RTT; the plan computed here is written as comments for the operator to check.
The settings are serialised (tomlwriter), never templated: a model string (the
configPath, the PubBroker's host) cannot add a key or a table."""

from __future__ import annotations

import json
from typing import Any

from ..artifact import Artifact
from ..context import Context
from ..render import render
from ..tomlwriter import dumps

ZENOH_LISTEN = "tcp/127.0.0.1:7447"


def config(ctx: Context) -> dict[str, Any]:
    """The settings of subbroker.toml (docs/subbroker.md)."""
    endpoint = ctx.model["pubBroker"]["endpoint"]
    link: dict[str, Any] = {
        "endpoint": f"{endpoint['host']}:{endpoint['port']}",
        "key": ctx.key_ref,
    }
    model_link = ctx.model.get("link", {})
    if model_link.get("transport", "tcp") != "tcp":
        link["transport"] = model_link["transport"]
        if model_link["transport"] == "serial":
            link["device"] = model_link["device"]
            link["baud"] = model_link.get("baud", 57600)
    return {
        "model": "model.json",
        "drone": ctx.drone,
        "state_dir": ctx.model["subBroker"]["configPath"],
        "link": link,
        "zenoh": {"mode": "peer", "listen": [ZENOH_LISTEN]},
        "delivery": {"zenoh": True, "tcp": True},
    }


def artifacts(ctx: Context) -> list[Artifact]:
    plan = ctx.plan.to_json()
    header = render("operator/subbroker.toml.j2", drone=ctx.drone, plan=plan, delays=plan["delays"])
    text = header + dumps(config(ctx))
    model_json = json.dumps(ctx.model, indent=2, ensure_ascii=False) + "\n"
    return [
        Artifact("operator/subbroker.toml", text, "operator"),
        Artifact("operator/model.json", model_json, "operator"),
    ]
