"""The SubBroker's configuration (TOML, docs/subbroker.md) and the model it
serves, for the operator. The SubBroker plans at run time with the measured
RTT; the plan computed here is written as comments for the operator to check."""

from __future__ import annotations

import json

from ..artifact import Artifact
from ..context import Context
from ..render import render

ZENOH_LISTEN = "tcp/127.0.0.1:7447"


def artifacts(ctx: Context) -> list[Artifact]:
    endpoint = ctx.model["pubBroker"]["endpoint"]
    plan = ctx.plan.to_json()
    text = render("operator/subbroker.toml.j2", drone=ctx.drone, key_ref=ctx.key_ref,
                  link_endpoint=f"{endpoint['host']}:{endpoint['port']}",
                  zenoh_listen=ZENOH_LISTEN, plan=plan, delays=plan["delays"],
                  state_dir=ctx.model["subBroker"]["configPath"])
    model_json = json.dumps(ctx.model, indent=2, ensure_ascii=False) + "\n"
    return [Artifact("operator/subbroker.toml", text, "operator"),
            Artifact("operator/model.json", model_json, "operator")]
