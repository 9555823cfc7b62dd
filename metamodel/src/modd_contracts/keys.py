"""The zenoh key expressions between the SubBroker, the backend and the other
base-station processes (docs/subbroker.md, "Zenoh keys"): the one place
where they are spelled. Builders check every name they put in a key, so a
model string can never widen a key expression (``*``, ``/``, ``**``).

>>> sub_key("usv", "sub_1")
'modd/usv/sub/sub_1'
>>> values_of("usv"), values_of(None)
('modd/usv/sub/*', 'modd/*/sub/*')
>>> parse_sub_key("modd/usv/sub/sub_1")
('usv', 'sub_1')
>>> match_status_key("modd/usv/status"), match_sub_key("modd/usv/status")
('usv', None)
"""

from __future__ import annotations

import re

#: The first chunk of every MoDD key.
ROOT = "modd"
#: The metamodel's ``Name`` (pattern and maxLength; a test holds them to the schema).
NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]{0,63}")


def check_name(kind: str, name: object) -> str:
    """``name`` if it is a model identifier (safe inside a key; the whole
    string must match, a trailing newline too), else ValueError."""
    if not isinstance(name, str) or not NAME.fullmatch(name):
        raise ValueError(
            f"{kind} {str(name)[:80]!r} is not an identifier (letters, digits, "
            "underscores, at most 64)"
        )
    return name


def drone_prefix(drone: str | None) -> str:
    """``modd/<drone>``, or ``modd/*`` (every drone) for ``None``."""
    return f"{ROOT}/{'*' if drone is None else check_name('drone', drone)}"


def sub_key(drone: str, subscriber: str) -> str:
    """Where the SubBroker puts the delivered values of one subscriber."""
    return f"{drone_prefix(drone)}/sub/{check_name('subscriber', subscriber)}"


def status_key(drone: str | None) -> str:
    """Where the SubBroker puts its status document (``None``: every drone's)."""
    return f"{drone_prefix(drone)}/status"


#: The last chunk of each of the SubBroker's queryables.
QUERYABLES = ("deploy", "subscribe", "backfill")


def deploy_key(drone: str) -> str:
    """The SubBroker's deploy queryable."""
    return f"{drone_prefix(drone)}/{QUERYABLES[0]}"


def subscribe_key(drone: str) -> str:
    """The SubBroker's dynamic-subscription queryable."""
    return f"{drone_prefix(drone)}/{QUERYABLES[1]}"


def backfill_key(drone: str) -> str:
    """The SubBroker's backfill queryable (start, progress, cancel)."""
    return f"{drone_prefix(drone)}/{QUERYABLES[2]}"


def queryables_of(drone: str | None) -> list[str]:
    """Every queryable of one drone's SubBroker (``None``: of every drone),
    for ACL rules."""
    return [f"{drone_prefix(drone)}/{q}" for q in QUERYABLES]


def values_of(drone: str | None) -> str:
    """Every subscriber's values of one drone (``None``: of every drone)."""
    return f"{drone_prefix(drone)}/sub/*"


def values_tree(drone: str | None) -> str:
    """``values_of`` and anything deeper (``modd/<drone>/sub/**``), for ACL rules."""
    return f"{drone_prefix(drone)}/sub/**"


def recovery_tree(drone: str | None) -> str:
    """The keys of zenoh's recovery of delivered values (``zenoh.ext`` advanced publishers
    and subscribers: ``modd/<drone>/sub/<subscriber>/@adv/...``), for ACL rules: ``@adv``
    is a verbatim chunk that no ``**`` matches.

    >>> recovery_tree(None)
    'modd/*/sub/*/@adv/**'
    """
    return f"{drone_prefix(drone)}/sub/*/@adv/**"


def fleet_tree(drone: str | None) -> str:
    """A drone's fleet keys (``modd/<drone>/fleet/**``): the liveliness tokens that elect
    the station serving it (docs/fleet.md), for ACL rules."""
    return f"{drone_prefix(drone)}/fleet/**"


def candidate_key(drone: str, station: str) -> str:
    """The liveliness token of a station that can serve ``drone``.

    >>> candidate_key("usv", "shore")
    'modd/usv/fleet/candidate/shore'
    """
    return f"{drone_prefix(drone)}/fleet/candidate/{check_name('station', station)}"


def serving_key(drone: str, station: str | None) -> str:
    """The liveliness token of the station holding ``drone``'s link (``None``: any)."""
    who = "*" if station is None else check_name("station", station)
    return f"{drone_prefix(drone)}/fleet/serving/{who}"


def held_key(drone: str, station: str | None) -> str:
    """The queryable of a station's window record for ``drone`` (``None``: every station's).

    >>> held_key("usv", None)
    'modd/usv/fleet/held/*'
    """
    who = "*" if station is None else check_name("station", station)
    return f"{drone_prefix(drone)}/fleet/held/{who}"


def heard_key(drone: str, station: str | None) -> str:
    """Where a standby station puts the drone's datagrams its modem heard, for the
    serving station (docs/fleet.md, "Diversity reception"; ``None``: every station's).

    >>> heard_key("usv", "boat")
    'modd/usv/fleet/heard/boat'
    """
    who = "*" if station is None else check_name("station", station)
    return f"{drone_prefix(drone)}/fleet/heard/{who}"


#: Everything under the MoDD root, for ACL rules.
EVERYTHING = f"{ROOT}/**"
#: Every drone's values and every drone's status: what readers subscribe to.
ALL_VALUES = values_of(None)
ALL_STATUS = status_key(None)


def match_sub_key(key: str) -> tuple[str, str] | None:
    """``(drone, subscriber)`` of a :func:`sub_key`, or ``None`` for any other
    key (what a subscription callback does with a key it did not expect)."""
    parts = key.split("/")
    if len(parts) != 4 or parts[0] != ROOT or parts[2] != "sub":
        return None
    drone, subscriber = parts[1], parts[3]
    return (drone, subscriber) if NAME.fullmatch(drone) and NAME.fullmatch(subscriber) else None


def match_status_key(key: str) -> str | None:
    """The drone of a :func:`status_key`, or ``None`` for any other key."""
    parts = key.split("/")
    if len(parts) != 3 or parts[0] != ROOT or parts[2] != "status":
        return None
    return parts[1] if NAME.fullmatch(parts[1]) else None


def parse_sub_key(key: str) -> tuple[str, str]:
    """``(drone, subscriber)`` of a :func:`sub_key`, else ValueError."""
    found = match_sub_key(key)
    if found is None:
        raise ValueError(f"{key[:200]!r} is not a {ROOT}/<drone>/sub/<subscriber> key")
    return found


def parse_status_key(key: str) -> str:
    """The drone of a :func:`status_key`, else ValueError."""
    found = match_status_key(key)
    if found is None:
        raise ValueError(f"{key[:200]!r} is not a {ROOT}/<drone>/status key")
    return found
