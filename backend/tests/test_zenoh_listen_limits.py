"""The backend, when it listens for zenoh peers, bounds connections that never
authenticate as the SubBroker does (docs/security.md, "Idle connections")."""

from __future__ import annotations

import json

import zenoh
from modd_backend.zenoh_session import zenoh_config


def test_listening_bounds_pending_connections_and_connecting_keeps_defaults() -> None:
    listening = json.loads(zenoh_config((), ("tcp/127.0.0.1:7999",)).get_json("transport/unicast"))
    assert listening["accept_timeout"] == 2000 and listening["accept_pending"] == 2000
    assert listening["max_sessions"] == 256
    connecting = zenoh_config(("tcp/127.0.0.1:7999",), ()).get_json("transport/unicast")
    assert connecting == zenoh.Config().get_json("transport/unicast")
