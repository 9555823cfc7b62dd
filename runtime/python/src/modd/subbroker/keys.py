"""The SubBroker's zenoh keys: defined once in :mod:`modd_contracts.keys`
(docs/architecture.md, "Contracts"); re-exported here for the SubBroker's
modules. A new key goes there, not here.

>>> sub_key("usv", "sub_1")
'modd/usv/sub/sub_1'
"""

from __future__ import annotations

from modd_contracts.keys import (
    backfill_key,
    check_name,
    deploy_key,
    status_key,
    sub_key,
    subscribe_key,
)

__all__ = ["check_name", "deploy_key", "status_key", "sub_key", "subscribe_key", "backfill_key"]
