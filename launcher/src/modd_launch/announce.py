"""What ``modd up`` says on the zenoh status key when it gives up a run
(docs/reliability.md, "Base station, store and tools"): the SubBroker that published the status is
stopped with the rest, so ``modd up`` opens a session where the SubBroker's was
(the same endpoints, the SubBroker's credentials) and puts, for a few seconds
so that reconnecting clients (the workbench) get it, a status whose
``supervisor`` field names the process, its exit code, the reason and its log.

>>> settings_for(["tcp/127.0.0.1:7447"], []).mode
'router'
"""

from __future__ import annotations

import json
import sys
import time
from collections.abc import Sequence
from typing import Any

from modd.subbroker.keys import status_key
from modd.zenoh_auth import CredentialStore
from modd.zenoh_session import DEFAULT_ENDPOINT, ZenohSettings, open_session, secured

#: How long the last status is put (every PERIOD_S): a client reconnects within it.
ANNOUNCE_S = 5.0
PERIOD_S = 0.5


def settings_for(listen: Sequence[str], connect: Sequence[str]) -> ZenohSettings:
    """The SubBroker's place on zenoh: a router on its listen endpoints, else a
    client of the router it connects to."""
    if connect and not listen:
        return ZenohSettings(mode="client", connect=tuple(connect))
    return ZenohSettings(mode="router", listen=tuple(listen or [DEFAULT_ENDPOINT]))


def stopped_status(drone: str, supervisor: dict[str, Any]) -> dict[str, Any]:
    """A status document (the contract's, ``status.schema.json``) of a stopped run."""
    return {
        "drone": drone,
        "time_ns": time.time_ns(),
        "link": "stopped",
        "endpoint": "",
        "rtt_s": None,
        "config_id": None,
        "epoch_ns": None,
        "bytes_in": 0,
        "bytes_out": 0,
        "data_frames": 0,
        "skipped_frames": 0,
        "connects": 0,
        "last_data_ns": None,
        "last_error": str(supervisor.get("reason", "")),
        "delivered": 0,
        "predicted_link_bytes_per_s": None,
        "routes": {},
        "dynamic": [],
        "tcp": {},
        "pubbroker": {},
        "supervisor": supervisor,
    }


def announce_stop(
    settings: ZenohSettings,
    store: CredentialStore,
    drone: str,
    supervisor: dict[str, Any],
    seconds: float = ANNOUNCE_S,
) -> bool:
    """Put the stopped run's status for ``seconds``; False (said on stderr) when no
    session could be opened."""
    try:
        session = open_session(secured(settings, store, "subbroker", drone))
    except (ValueError, OSError) as exc:
        print(f"modd up: the stop could not be said on zenoh: {exc}", file=sys.stderr)
        return False
    payload = json.dumps(stopped_status(drone, supervisor))
    try:
        pub = session.declare_publisher(status_key(drone))
        end = time.monotonic() + seconds
        while True:
            pub.put(payload)
            if time.monotonic() >= end:
                return True
            time.sleep(PERIOD_S)
    finally:
        session.close()  # type: ignore[no-untyped-call]
