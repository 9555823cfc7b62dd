"""The PubBroker's configuration file (format: docs/pubbroker.md), for the operator."""

from __future__ import annotations

import json
from typing import Any

from modd_contracts.schema import load
from modd_plan.linkbudget import LinkSettings

from ..artifact import Artifact
from ..context import Context


def _default(obj: str, key: str) -> Any:
    """A default of the pubbroker.json contract (the PubBroker's own, config.hpp)."""
    schema = load("pubbroker")
    props = schema["properties"] if not obj else schema["$defs"][obj]["properties"]
    return props[key]["default"]


# Archive rotation and reporting defaults for a mission: hourly files of at most
# 256 MiB, fsync at every chunk so that a power cut loses at most one chunk.
ROTATE_BYTES = _default("PubBrokerArchive", "rotate_bytes")
ROTATE_S = _default("PubBrokerArchive", "rotate_s")
STATUS_PERIOD_S = _default("", "status_period_s")
LOG_PERIOD_S = _default("", "log_period_s")
DEFAULT_BUFFER_SIZE = _default("", "default_buffer_size")
# Ingress rules (docs/ingress.md): a sample's timestamp is judged against the drone's clock;
# refused only beyond 10 s ahead or 1 h behind. The operator is warned under 256 MiB free.
MAX_FUTURE_MS = _default("PubBrokerIngress", "max_future_ms")
MAX_PAST_MS = _default("PubBrokerIngress", "max_past_ms")
LOW_SPACE_MB = _default("PubBrokerArchive", "low_space_mb")


def link_transport(model: dict[str, Any]) -> dict[str, Any]:
    """The link's transport keys for the PubBroker (docs/pubbroker.md, "link"):
    nothing for tcp (the default), else transport, packet, accepted delay and,
    for serial, the on-board device and its baud rate."""
    link = model.get("link", {})
    transport = link.get("transport", "tcp")
    if transport == "tcp":
        return {}
    settings = LinkSettings.of(model)
    out: dict[str, Any] = {
        "transport": transport,
        "max_packet": settings.max_packet,
        "delay_ms": int(settings.accepted_delay * 1000),
    }
    if transport == "serial":
        out["device"] = link.get("droneDevice") or link["device"]
        out["baud"] = link.get("baud", 57600)
    return out


def config(ctx: Context) -> dict[str, Any]:
    broker = ctx.model["pubBroker"]
    sizes = ctx.plan.buffer_sizes
    ingress: dict[str, Any] = {
        "unix_path": ctx.ingress.unix_socket,
        "max_future_ms": MAX_FUTURE_MS,
        "max_past_ms": MAX_PAST_MS,
    }
    if ctx.ingress.tcp_port:
        ingress.update(host=ctx.ingress.tcp_host, port=ctx.ingress.tcp_port)
    return {
        "name": ctx.drone,
        "link": {
            "host": broker["endpoint"]["host"],
            "port": broker["endpoint"]["port"],
            "key": ctx.key_ref,
            **link_transport(ctx.model),
        },
        "ingress": ingress,
        "archive": {
            "dir": broker["logPath"],
            "prefix": ctx.drone,
            "rotate_bytes": ROTATE_BYTES,
            "rotate_s": ROTATE_S,
            "fsync": "chunk",
            "compression": "zstd",
            "low_space_mb": LOW_SPACE_MB,
        },
        "topics": [
            {"name": t.name, "type": t.type, "buffer_size": sizes.get(t.name, DEFAULT_BUFFER_SIZE)}
            for t in ctx.topics.values()
            if t.publisher is not None
        ],
        "default_buffer_size": DEFAULT_BUFFER_SIZE,
        "status_period_s": STATUS_PERIOD_S,
        "log_period_s": LOG_PERIOD_S,
    }


def artifacts(ctx: Context) -> list[Artifact]:
    text = json.dumps(config(ctx), indent=2) + "\n"
    return [Artifact("operator/pubbroker.json", text, "operator")]
