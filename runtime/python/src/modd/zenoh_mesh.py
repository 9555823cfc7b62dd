"""Several base stations, one zenoh router mesh (docs/fleet.md): each station's
router (a SubBroker in router mode, or ``python -m modd.station``) connects to
the other stations' routers with zenoh's own routing, under the same
authentication and access control as its clients. No relay of our own.

A station has a zenoh id (``id``, hex) and knows the others' ids and endpoints
(``peers``). It connects to every peer; the pair keeps one session whichever side
opened it. The side that accepts authenticates the other as the ``station`` user
(the campaign's one ``station.cred``, copied to every station); the side that
connected knows the other by its zenoh id, the endpoint it chose to dial. The
``station`` policy lets stations exchange everything under ``modd/**`` (values,
status, queryables, liveliness), nothing else.

>>> m = Mesh.from_mapping({"id": "a1", "peers": {"b2": "tcp/127.0.0.2:7447"}})
>>> m.endpoints(), m.peer_ids()
(('tcp/127.0.0.2:7447',), ('b2',))
>>> Mesh.from_mapping({"id": "x"})
Traceback (most recent call last):
ValueError: zenoh.mesh.id: 'x' is not a zenoh id (1 to 32 hex digits, not all zero)
"""

from __future__ import annotations

import copy
import json
import re
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from modd_contracts import keys

from .zenoh_auth import STATION_IDENTITY

#: The user stations give each other (its ``.cred`` file in the credentials directory).
STATION = STATION_IDENTITY
#: A zenoh id: hex, at most 16 bytes, not zero.
ZID = re.compile(r"[0-9a-f]{1,32}")
#: What one station may send to and receive from another, on ``modd/**`` only.
STATION_MESSAGES = [
    "put",
    "delete",
    "declare_subscriber",
    "query",
    "declare_queryable",
    "reply",
    "liveliness_token",
    "declare_liveliness_subscriber",
    "liveliness_query",
]


def check_zid(value: object, where: str) -> str:
    if not isinstance(value, str) or not ZID.fullmatch(value) or not value.strip("0"):
        raise ValueError(f"{where}: {value!r} is not a zenoh id (1 to 32 hex digits, not all zero)")
    return value


@dataclass(frozen=True)
class Mesh:
    """This station's zenoh id and the other stations' (id -> endpoint)."""

    station: str
    peers: Mapping[str, str] = field(default_factory=dict)

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "zenoh.mesh") -> Mesh:
        """From ``[zenoh.mesh]``: ``id = "a1"``, ``peers = {b2 = "tcp/host:7447"}``."""
        unknown = sorted(set(data) - {"id", "peers"})
        if unknown:
            raise ValueError(f"{where}: unknown key {unknown[0]!r}; known: id, peers")
        station = check_zid(data.get("id"), f"{where}.id")
        peers = data.get("peers", {})
        if not isinstance(peers, Mapping):
            raise ValueError(f"{where}.peers: expected a table of zenoh id = endpoint")
        for zid, endpoint in peers.items():
            check_zid(zid, f"{where}.peers")
            if not isinstance(endpoint, str) or "/" not in endpoint:
                raise ValueError(f"{where}.peers.{zid}: expected an endpoint such as tcp/host:7447")
        if station in peers:
            raise ValueError(f"{where}.peers: {station} is this station's own id")
        return cls(station, dict(peers))

    def endpoints(self) -> tuple[str, ...]:
        return tuple(self.peers.values())

    def peer_ids(self) -> tuple[str, ...]:
        return tuple(self.peers)

    def inserts(self) -> dict[str, str]:
        """The zenoh settings of a station in the mesh: its id (the others' ACL names it)."""
        return {"id": json.dumps(self.station)}


def station_acl(base: Mapping[str, Any], peer_ids: tuple[str, ...]) -> dict[str, Any]:
    """``base`` (:func:`modd.zenoh_auth.acl`) with the ``station`` policy: the stations
    that connect here (user ``station``) and those this one connects to (by zenoh id)
    may exchange anything under ``modd/**``, both ways."""
    out = copy.deepcopy(dict(base))
    out["rules"].append(
        {
            "id": "station_mesh",
            "messages": STATION_MESSAGES,
            "flows": ["ingress", "egress"],
            "permission": "allow",
            # zenoh's recovery keys are verbatim (@adv): no ** matches them
            "key_exprs": [keys.EVERYTHING, keys.recovery_tree(None)],
        }
    )
    subjects = [{"id": "station_user", "usernames": [STATION]}]
    if peer_ids:
        subjects.append({"id": "station_peers", "zids": list(peer_ids)})
    out["subjects"] += subjects
    out["policies"].append(
        {"id": "station", "rules": ["station_mesh"], "subjects": [s["id"] for s in subjects]}
    )
    return out
