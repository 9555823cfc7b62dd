"""A campaign's base stations (docs/fleet.md, docs/operations.md "Two stations"):
``modd generate FILE --out DIR --station shore=tcp/shore.example:7447 --station boat``
writes one SubBroker configuration per station, ``operator/stations/<name>/subbroker.toml``:
the drone's (subbroker_config.py) with ``station`` set, its zenoh in router mode (the
SubBroker is the station's router) and ``[zenoh.mesh]``: this station's zenoh id and
the other stations' endpoints. A station given without an endpoint (behind a cellular
link or NAT: nothing can connect to it) dials the others and is listed by none.

A model with a ``Campaign`` (several vehicles: modd_model.campaign) gets, per station,
a folder to copy to that station: the router's ``station.toml`` (for ``modd-station
--config``: ``[zenoh]`` listen and mesh, as above) and, per vehicle,
``vehicles/<vehicle>/subbroker.toml`` (a client of that router, as ``modd up`` runs a
campaign) with the vehicle's ``model.json`` beside it. Every station gets every
vehicle: any may hear any drone, and one that never hears a vehicle stands by for it.

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
import json
import re
from collections import Counter
from dataclasses import dataclass
from pathlib import PurePosixPath
from typing import Any

from modd_model.campaign import expand, vehicles

from ..artifact import Artifact
from ..context import DEFAULT_KEY_REF, Context, build_context
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


def artifacts(model: dict[str, Any], stations: list[CampaignStation]) -> list[Artifact]:
    """The stations' files: for the drone of ``model``, or for each of its campaign's
    vehicles when it has one."""
    check_campaign(stations)
    if vehicles(model):
        return campaign_artifacts(model, stations)
    ctx = build_context(model)
    out = []
    for me in stations:
        text = _head(me, stations) + dumps(config(ctx, me, stations))
        out.append(Artifact(f"operator/stations/{me.name}/subbroker.toml", text, "operator"))
    return out


def _head(me: CampaignStation, stations: list[CampaignStation]) -> str:
    how = (
        f"reached by the others at {me.endpoint}"
        if me.endpoint
        else "behind a cellular link or NAT: it dials the others, none dials it"
    )
    return (
        f"# Station {me.name} of the campaign ({', '.join(s.name for s in stations)}): "
        f"{how}.\n# Copy the first station's credentials directory to every station "
        "(docs/fleet.md, 'One mesh of stations').\n"
    )


def local_endpoint(listen: str) -> str:
    """Where a process on the station's own machine reaches its router.

    >>> local_endpoint("tcp/0.0.0.0:7447")
    'tcp/127.0.0.1:7447'
    """
    proto, _, rest = listen.partition("/")
    return f"{proto}/127.0.0.1:{rest.rsplit(':', 1)[1]}"


def router_config(me: CampaignStation, stations: list[CampaignStation]) -> dict[str, Any]:
    """A campaign station's router (``python -m modd.station --config``)."""
    peers = {s.zid: s.endpoint for s in stations if s is not me and s.endpoint is not None}
    return {"zenoh": {"listen": [me.listen], "mesh": {"id": me.zid, "peers": peers}}}


def vehicle_config(
    ctx: Context, vehicle: str, me: CampaignStation, shared_state: bool = False
) -> dict[str, Any]:
    """One vehicle's SubBroker at station ``me``: a client of the station's router.
    ``shared_state``: other vehicles have the same SubBroker path (the mission's, not
    one of their own); its state then goes in a folder named after the vehicle, as two
    SubBrokers on one window record would each take the other's windows as theirs."""
    doc = subbroker_config.config(ctx)
    if shared_state:
        doc["state_dir"] = str(PurePosixPath(doc["state_dir"]) / vehicle)
    doc["model"] = "model.json"  # beside it
    doc["station"] = me.name
    doc["zenoh"] = {"mode": "client", "listen": [], "connect": [local_endpoint(me.listen)]}
    if ctx.key_ref == DEFAULT_KEY_REF:  # one station, several drones: a key each
        doc["link"]["key"] = vehicle_key_ref(vehicle)
    return doc


def vehicle_key_ref(vehicle: str) -> str:
    """Where a vehicle's SubBroker reads its link key when its model names none.

    >>> vehicle_key_ref("usv1")
    'env:MODD_LINK_KEY_USV1'
    """
    return f"{DEFAULT_KEY_REF}_{vehicle.upper()}"


def campaign_artifacts(model: dict[str, Any], stations: list[CampaignStation]) -> list[Artifact]:
    fleet = expand(model)
    paths = Counter(str(vm["subBroker"]["configPath"]) for vm in fleet.values())
    out = []
    for me in stations:
        where = f"operator/stations/{me.name}"
        start = (
            "# Copy this folder to the station. Start: modd-station --config station.toml\n"
            "# --credentials DIR, then each vehicle's modd-subbroker --config\n"
            "# vehicles/<vehicle>/subbroker.toml --credentials DIR (one DIR for all).\n"
        )
        text = _head(me, stations) + start + dumps(router_config(me, stations))
        out.append(Artifact(f"{where}/station.toml", text, "operator"))
        for name, vm in fleet.items():
            head = (
                f"# Vehicle {name} at station {me.name}: a client of the station's router "
                f"({local_endpoint(me.listen)}); its link key as [link] key says.\n"
            )
            shared = paths[str(vm["subBroker"]["configPath"])] > 1
            text = head + dumps(vehicle_config(build_context(vm), name, me, shared))
            out.append(Artifact(f"{where}/vehicles/{name}/subbroker.toml", text, "operator"))
            body = json.dumps(vm, indent=2, ensure_ascii=False) + "\n"
            out.append(Artifact(f"{where}/vehicles/{name}/model.json", body, "operator"))
    return out
