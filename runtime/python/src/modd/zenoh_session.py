"""Zenoh sessions for MoDD processes, with the embedded defaults of
docs/subbroker.md: peer mode, multicast scouting off, ``scouting/delay`` 0,
loopback endpoints. Client/router mode, user-password authentication and TLS
pass through as raw zenoh settings for multi-host deployments.

>>> s = ZenohSettings(listen=("tcp/127.0.0.1:7447",))
>>> s.inserts()["scouting/multicast/enabled"]
'false'
"""

from __future__ import annotations

import json
import time
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import zenoh

#: Where a SubBroker listens by default, and where clients connect by default.
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
MODES = ("peer", "client", "router")
RECONNECT = "{period_init_ms: 100, period_max_ms: 1000, period_increase_factor: 2}"


@dataclass(frozen=True)
class ZenohSettings:
    """How to open a zenoh session.

    ``extra`` maps zenoh configuration paths to JSON5 values inserted last
    (e.g. ``{"transport/auth/usrpwd/user": '"base"'}``); ``config_file`` is a
    full zenoh JSON5 configuration to start from.
    """

    mode: str = "peer"
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    config_file: str | None = None
    extra: Mapping[str, str] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"zenoh mode {self.mode!r}: expected one of {', '.join(MODES)}")

    def inserts(self) -> dict[str, str]:
        """Configuration path -> JSON5 value, in the order they are applied."""
        out = {
            "mode": json.dumps(self.mode),
            "scouting/multicast/enabled": "false",
            "scouting/delay": "0",
        }
        if self.listen or self.mode != "client":
            out["listen/endpoints"] = json.dumps(list(self.listen))
        if self.connect:
            out["connect/endpoints"] = json.dumps(list(self.connect))
            # come back within a second when the other side restarts
            out["connect/retry"] = RECONNECT
        out.update(self.extra)
        return out

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "zenoh") -> ZenohSettings:
        """From a config-file table (docs/subbroker.md, ``[zenoh]``)."""
        known = {"mode", "listen", "connect", "config_file", "settings"}
        unknown = sorted(set(data) - known)
        if unknown:
            listing = ", ".join(sorted(known))
            raise ValueError(f"{where}: unknown key {unknown[0]!r}; known: {listing}")
        extra = data.get("settings", {})
        if not isinstance(extra, Mapping):
            raise ValueError(f"{where}.settings: expected a table of path = value")
        return cls(
            mode=str(data.get("mode", "peer")),
            listen=tuple(_str_list(data.get("listen", [DEFAULT_ENDPOINT]), f"{where}.listen")),
            connect=tuple(_str_list(data.get("connect", []), f"{where}.connect")),
            config_file=data.get("config_file"),
            extra={k: json.dumps(v) for k, v in extra.items()},  # TOML values -> JSON
        )


def _str_list(value: Any, where: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError(f"{where}: expected a list of endpoints such as {DEFAULT_ENDPOINT!r}")
    return list(value)


def client_settings(connect: str | None = None) -> ZenohSettings:
    """Settings for a consumer on the base station: a peer that listens
    nowhere and connects to the SubBroker (``MODD_ZENOH_CONNECT`` or
    :data:`DEFAULT_ENDPOINT` when ``connect`` is not given)."""
    import os

    endpoint = connect or os.environ.get("MODD_ZENOH_CONNECT") or DEFAULT_ENDPOINT
    return ZenohSettings(mode="peer", connect=(endpoint,))


def zenoh_config(settings: ZenohSettings) -> zenoh.Config:
    """A ``zenoh.Config`` for these settings."""
    import zenoh

    path = settings.config_file
    config = zenoh.Config.from_file(path) if path else zenoh.Config()
    for key, value in settings.inserts().items():
        try:
            config.insert_json5(key, value)
        except Exception as exc:  # zenoh raises ZError with the bare path
            raise ValueError(f"zenoh setting {key} = {value}: {exc}") from exc
    return config


def open_session(settings: ZenohSettings) -> zenoh.Session:
    """Open a session; raises ValueError naming the endpoints if it cannot."""
    import zenoh

    try:
        return zenoh.open(zenoh_config(settings))
    except zenoh.ZError as exc:
        where = ", ".join(settings.listen + settings.connect) or "no endpoint"
        raise ValueError(f"cannot open a zenoh session ({settings.mode}, {where}): {exc}") from exc


def wait_connected(session: zenoh.Session, timeout_s: float = 5.0) -> bool:
    """Wait until the session sees a peer or a router (a get sent before that
    finds no queryable and returns nothing). True when connected."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        info = session.info
        if list(info.peers_zid()) or list(info.routers_zid()):
            return True
        time.sleep(0.01)
    return False
