"""``python -m modd.station``: a base station's zenoh router, for a station whose
drones' SubBrokers join it as clients (docs/fleet.md). It authenticates and applies
the access control of a SubBroker's router for every drone (docs/security.md) and,
with ``--id`` and ``--peer``, joins the other stations' routers in one mesh.

    python -m modd.station --listen tcp/0.0.0.0:7447 --credentials DIR \\
        --id a1 --peer b2=tcp/station-b.example:7447 --peer c3=tcp/station-c.example:7447
    python -m modd.station --config station.toml --credentials DIR

``--config``: a TOML file whose ``[zenoh]`` table is a SubBroker's (``listen``,
``[zenoh.mesh]`` ``id`` and ``peers``, ``settings``, ``gate``: docs/subbroker.md), as
``modd generate --station`` writes it for a campaign; ``--listen``, ``--id`` and
``--peer`` given as well replace what it says.

SIGTERM or SIGINT stops it. Exit codes: 0 stopped, 2 bad usage or configuration.
"""

from __future__ import annotations

import argparse
import logging
import sys
import threading
import tomllib
from dataclasses import replace
from pathlib import Path

from .shutdown import stop_on_signals
from .zenoh_auth import CredentialStore
from .zenoh_gate import start_gates
from .zenoh_mesh import Mesh
from .zenoh_session import DEFAULT_ENDPOINT, ZenohSettings, open_session, secured


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="modd.station", description=__doc__.splitlines()[0])
    p.add_argument("--config", metavar="FILE", help="a station.toml ([zenoh], its mesh)")
    p.add_argument("--listen", action="append", metavar="ENDPOINT", help="repeatable")
    p.add_argument("--credentials", required=True, metavar="DIR", help="credentials directory")
    p.add_argument("--id", metavar="HEX", help="this station's zenoh id (the mesh)")
    p.add_argument(
        "--peer", action="append", default=[], metavar="ID=ENDPOINT", help="another station"
    )
    p.add_argument("--log-level", default="INFO")
    return p


def settings_of(args: argparse.Namespace) -> ZenohSettings:
    """The router's settings (ValueError, located, for a bad file, --id or --peer)."""
    base = ZenohSettings(mode="router", listen=(DEFAULT_ENDPOINT,))
    if args.config:
        base = replace(read_config(Path(args.config)), mode="router")
    mesh = base.mesh
    if args.id or args.peer:
        peers = dict(p.split("=", 1) for p in args.peer if "=" in p)
        if len(peers) != len(args.peer):
            raise ValueError("--peer: expected ID=ENDPOINT, e.g. b2=tcp/station-b.example:7447")
        mesh = Mesh.from_mapping({"id": args.id, "peers": peers}, "--id/--peer")
    listen = tuple(args.listen) if args.listen else base.listen
    return replace(base, listen=listen, mesh=mesh)


def read_config(path: Path) -> ZenohSettings:
    """A station.toml's ``[zenoh]`` (its only table)."""
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise ValueError(f"{path}: cannot read: {exc}") from exc
    except tomllib.TOMLDecodeError as exc:
        raise ValueError(f"{path}: {exc}") from exc
    unknown = sorted(set(doc) - {"zenoh"})
    if unknown:
        raise ValueError(f"{path}: unknown table {unknown[0]!r}; known: zenoh")
    table = doc.get("zenoh", {})
    if not isinstance(table, dict):
        raise ValueError(f"{path}: zenoh: expected a table")
    mode = table.get("mode", "router")
    if mode != "router":
        raise ValueError(f"{path}: zenoh.mode: a station is a router, not {mode!r}")
    return ZenohSettings.from_mapping(table, f"{path}: zenoh")


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    logging.basicConfig(level=args.log_level.upper(), format="%(asctime)s modd.station %(message)s")
    try:
        store = CredentialStore(args.credentials)
        settings, gates = start_gates(secured(settings_of(args), store, "station", None))
        session = open_session(settings)
    except ValueError as exc:
        print(f"modd.station: {exc}", file=sys.stderr)
        return 2
    done = threading.Event()
    stop_on_signals(done)
    logging.getLogger("modd.station").info("station router up: %s", ", ".join(settings.listen))
    done.wait()
    session.close()  # type: ignore[no-untyped-call]
    for gate in gates:
        gate.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
