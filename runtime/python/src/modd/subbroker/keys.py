"""The zenoh key expressions of a SubBroker (docs/subbroker.md, "Zenoh keys").

>>> sub_key("usv", "sub_1")
'modd/usv/sub/sub_1'
"""

from __future__ import annotations

import re

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_name(kind: str, name: str) -> str:
    """``name`` if it is a model identifier (safe inside a key; the whole
    string must match, a trailing newline too), else ValueError."""
    if not _NAME.fullmatch(name):
        raise ValueError(f"{kind} {name!r} is not an identifier (letters, digits, underscores)")
    return name


def sub_key(drone: str, subscriber: str) -> str:
    """Where the values of one subscriber are put."""
    return f"modd/{check_name('drone', drone)}/sub/{check_name('subscriber', subscriber)}"


def status_key(drone: str) -> str:
    """Where the SubBroker puts its status, periodically."""
    return f"modd/{check_name('drone', drone)}/status"


def deploy_key(drone: str) -> str:
    """The deploy queryable."""
    return f"modd/{check_name('drone', drone)}/deploy"


def subscribe_key(drone: str) -> str:
    """The dynamic-subscription queryable."""
    return f"modd/{check_name('drone', drone)}/subscribe"


def backfill_key(drone: str) -> str:
    """The backfill queryable (start, progress, cancel)."""
    return f"modd/{check_name('drone', drone)}/backfill"
