"""Where publishers reach the PubBroker: the model's ingress settings, or
defaults derived from the model so that generated configs and stubs agree
(a model query: the generators and the runtime's bridges read it)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any


@dataclass(frozen=True)
class Ingress:
    unix_socket: str
    tcp_host: str
    tcp_port: int | None

    @property
    def address(self) -> str:
        """The publisher clients' address form: ``unix:PATH`` (preferred on board)."""
        return f"unix:{self.unix_socket}"


def ingress_of(model: dict[str, Any]) -> Ingress:
    broker = model["pubBroker"]
    ingress = broker.get("ingress", {})
    default_socket = f"/tmp/modd/{model['drone']['name']}/ingress.sock"
    return Ingress(
        unix_socket=ingress.get("unixSocket", default_socket),
        tcp_host=broker["endpoint"]["host"],
        tcp_port=ingress.get("tcpPort"),
    )
