"""A campaign's base stations (docs/fleet.md, docs/operations.md "Two stations"):
``modd generate FILE --out DIR --station shore=tcp/shore.example:7447 --station boat``
writes one SubBroker configuration per station, ``operator/stations/<name>/subbroker.toml``:
the drone's (subbroker_config.py) with ``station`` set, its zenoh in router mode (the
SubBroker is the station's router) and ``[zenoh.mesh]``: this station's zenoh id and
the other stations' endpoints. A station given without an endpoint (behind a cellular
link or NAT: nothing can connect to it) dials the others and is listed by none.

>>> s = parse_station("shore=tcp/shore.example:7447"); (s.name, s.endpoint, s.listen)
('shore', 'tcp/shore.example:7447', 'tcp/0.0.0.0:7447')
>>> parse_station("boat").endpoint is None
True
>>> parse_station("shore=shore.example")  # doctest: +ELLIPSIS
Traceback (most recent call last):
ValueError: --station shore=shore.example: expected NAME=PROTOCOL/HOST:PORT ...
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from typing import Any

from ..artifact import Artifact
from ..context import Context
from ..tomlwriter import dumps
from . import subbroker_config

_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_]{0,31}")
_ENDPOINT = re.compile(r"(tcp|tls|quic)/(\[[0-9a-fA-F:]+\]|[A-Za-z0-9.-]+):(\d{1,5})")
#: A station without an endpoint still listens (its own drones' SubBrokers, viewers).
DIAL_OUT_LISTEN = "tcp/0.0.0.0:7447"


@dataclass(frozen=True)
class CampaignStation:
    name: str
    endpoint: str | None  # where the others reach it; None: it dials out only

    @property
    def listen(self) -> str:
        if self.endpoint is None:
            return DIAL_OUT_LISTEN
        proto, _, rest = self.endpoint.partition("/")
        return f"{proto}/0.0.0.0:{rest.rsplit(':', 1)[1]}"

    @property
    def zid(self) -> str:
        """A zenoh id from the name: the same at every station that computes it."""
        return hashlib.sha256(self.name.encode()).hexdigest()[:16].lstrip("0") or "1"


def parse_station(text: str) -> CampaignStation:
    """``NAME=ENDPOINT`` or ``NAME``; ValueError naming the bad one."""
    name, sep, endpoint = text.partition("=")
    if not _NAME.fullmatch(name):
        raise ValueError(
            f"--station {text}: the name must be a letter then letters, digits or _ (at most 32)"
        )
    if not sep:
        return CampaignStation(name, None)
    m = _ENDPOINT.fullmatch(endpoint)
    if m is None or not 0 < int(m.group(3)) < 65536:
        raise ValueError(
            f"--station {text}: expected NAME=PROTOCOL/HOST:PORT (tcp/shore.example:7447), or NAME "
            "alone for a station nothing can connect to (cellular)"
        )
    return CampaignStation(name, endpoint)


def check_campaign(stations: list[CampaignStation]) -> None:
    names = [s.name for s in stations]
    if len(stations) < 2:
        raise ValueError("--station: a campaign's mesh needs two stations or more")
    if len(set(names)) < len(names):
        raise ValueError(f"--station: a name given twice ({', '.join(names)})")
    if all(s.endpoint is None for s in stations):
        raise ValueError("--station: no station has an endpoint: none could connect to another")


def config(ctx: Context, me: CampaignStation, stations: list[CampaignStation]) -> dict[str, Any]:
    """One station's subbroker.toml settings."""
    doc = subbroker_config.config(ctx)
    doc["model"] = "../../model.json"  # operator/model.json, beside the drone's own
    doc["station"] = me.name
    peers = {s.zid: s.endpoint for s in stations if s is not me and s.endpoint is not None}
    doc["zenoh"] = {"mode": "router", "listen": [me.listen], "mesh": {"id": me.zid, "peers": peers}}
    return doc


def artifacts(ctx: Context, stations: list[CampaignStation]) -> list[Artifact]:
    check_campaign(stations)
    out = []
    for me in stations:
        how = (
            f"reached by the others at {me.endpoint}"
            if me.endpoint
            else "behind a cellular link or NAT: it dials the others, none dials it"
        )
        head = (
            f"# Station {me.name} of the campaign ({', '.join(s.name for s in stations)}): "
            f"{how}.\n# Copy the first station's credentials directory to every station "
            "(docs/fleet.md, 'One mesh of stations').\n"
        )
        text = head + dumps(config(ctx, me, stations))
        out.append(Artifact(f"operator/stations/{me.name}/subbroker.toml", text, "operator"))
    return out
