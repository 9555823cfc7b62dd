"""The zenoh credentials of docker-compose.yml (docs/docker.md, docs/security.md):
made once in a volume, before the router starts.

    python docker/credentials.py DIR --drone usv

Makes (when missing) the credentials directory DIR (0700): ``users`` (the
router's dictionary), ``subbroker.cred``, ``backend.cred``, ``viewer.cred`` and
``deploy.key`` (0600), and writes ``DIR/router.json5``, the zenohd
configuration that authenticates every client with that dictionary and
applies the access control of the drone (modd.zenoh_auth.acl). Prints the
files' names, never a password.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path

from modd.zenoh_auth import CredentialStore, acl
from modd.zenoh_session import LISTENER_LIMITS


def router_config(store: CredentialStore, drone: str | None) -> dict[str, object]:
    # bounds against idle connections, as the SubBroker's (docs/security.md)
    unicast = {k.rsplit("/", 1)[1]: json.loads(v) for k, v in LISTENER_LIMITS.items()}
    return {
        "mode": "router",
        "scouting": {"multicast": {"enabled": False}, "gossip": {"enabled": False}},
        "transport": {
            "auth": {"usrpwd": {"dictionary_file": str(store.dictionary)}},
            "unicast": unicast,
        },
        "access_control": acl(drone),
    }


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="credentials.py", description=__doc__.splitlines()[0])
    p.add_argument("dir", metavar="DIR", help="the credentials directory (in a volume)")
    p.add_argument("--drone", help="the drone whose SubBroker may put (default: any)")
    args = p.parse_args(argv)
    store = CredentialStore(args.dir).ensure()
    config = store.dir / "router.json5"
    tmp = config.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    with os.fdopen(fd, "w") as out:
        json.dump(router_config(store, args.drone), out, indent=2)
    tmp.replace(config)
    names = sorted(f.name for f in Path(store.dir).iterdir())
    print(f"credentials: {store.dir}: {', '.join(names)}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
