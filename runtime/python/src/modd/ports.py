"""Loopback ports free right now, for local runs (``modd up``) and the tests, so
that two runs at once on one machine do not collide."""

from __future__ import annotations

import socket
from typing import Literal


def free_port(kind: Literal["tcp", "udp"] = "tcp") -> int:
    """A port on 127.0.0.1 that the system reports free at this instant."""
    family = socket.SOCK_STREAM if kind == "tcp" else socket.SOCK_DGRAM
    with socket.socket(socket.AF_INET, family) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])
