"""``modd-backend``: run the service (loopback unless told otherwise).

modd-backend --host 127.0.0.1 --port 8000 --data ./data
modd-backend backup --data ./data FILE     # and restore: see backup.py
"""

from __future__ import annotations

import argparse
import copy
import ipaddress
import logging
import os
import sys
from pathlib import Path
from typing import Any

from sqlalchemy.engine import make_url
from sqlalchemy.exc import ArgumentError

from .settings import DEFAULT_ZENOH_CONNECT, Settings, check_origin
from .storeproc import MAX_STORE_PROCESSES
from .zenoh_session import read_secret


def _has_password(url: str) -> bool:
    try:
        return bool(make_url(url).password)
    except ArgumentError:
        return False


def parse_args(argv: list[str] | None = None) -> Settings:
    p = argparse.ArgumentParser(prog="modd-backend", description=__doc__.splitlines()[0])
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default loopback)")
    p.add_argument("--port", type=int, default=8000)
    p.add_argument("--data", type=Path, default=Path("data"), help="data directory")
    p.add_argument(
        "--database-url",
        default=os.environ.get("MODD_DATABASE_URL"),
        help="SQLAlchemy URL (default: $MODD_DATABASE_URL, else a SQLite file in "
        "--data); a URL with a password belongs in the environment, not here",
    )
    p.add_argument(
        "--zenoh-connect",
        action="append",
        metavar="ENDPOINT",
        help=f"zenoh endpoint to connect to (default {DEFAULT_ZENOH_CONNECT[0]})",
    )
    p.add_argument("--zenoh-listen", action="append", metavar="ENDPOINT", default=[])
    p.add_argument(
        "--zenoh-credentials",
        type=Path,
        default=os.environ.get("MODD_ZENOH_CREDENTIALS") or None,
        metavar="FILE",
        help="the backend's zenoh user:password file (default "
        "$MODD_ZENOH_CREDENTIALS; docs/security.md)",
    )
    p.add_argument(
        "--deploy-key",
        type=Path,
        default=os.environ.get("MODD_DEPLOY_KEY") or None,
        metavar="FILE",
        help="key file that signs deploys, the SubBroker's deploy.key (default $MODD_DEPLOY_KEY)",
    )
    p.add_argument(
        "--link-keys",
        type=Path,
        metavar="DIR",
        help="the drones' link keys, <drone>.key, made at pairing (default DATA/pairing/link-keys)",
    )
    p.add_argument(
        "--pairing-key",
        type=Path,
        metavar="FILE",
        help="Ed25519 key signing pairing bundles, made at first use "
        "(default DATA/pairing/station.key)",
    )
    p.add_argument("--no-zenoh", action="store_true", help="no zenoh session (no deploy/streams)")
    p.add_argument(
        "--frontend",
        type=Path,
        default=Path("frontend/dist"),
        help="built frontend to serve at / when it exists",
    )
    p.add_argument("--archives", type=Path, help="archive directory (default DATA/archives)")
    p.add_argument(
        "--records", type=Path, help="base-station records directory (default DATA/records)"
    )
    p.add_argument("--deploy-timeout", type=float, default=10.0, help="seconds")
    p.add_argument(
        "--scene-port",
        type=int,
        default=0,
        help="port of the 3D scene (viser); 0: any free port; -1: no scene",
    )
    p.add_argument(
        "--foxglove-port",
        type=int,
        default=8765,
        help="loopback port of the Foxglove server (live values for Foxglove and "
        "Lichtblick); viewers connect through /foxglove/live with a ticket "
        "(docs/ecosystem.md); 0: none",
    )
    p.add_argument(
        "--foxglove-replay-port",
        type=int,
        default=8865,
        help="loopback port of the Foxglove replay of an archive chosen in the "
        "workbench (viewers connect through /foxglove/replay); 0: none",
    )
    p.add_argument(
        "--store-processes",
        type=_store_processes,
        default=os.environ.get("MODD_STORE_PROCESSES", "2"),
        metavar="N",
        help="processes running the model reads and saves, apart from the event loop "
        "($MODD_STORE_PROCESSES, default 2); 0: threads of the service's process",
    )
    p.add_argument(
        "--admin-password-file",
        type=Path,
        metavar="FILE",
        help="file holding the first admin's password (first line)",
    )
    p.add_argument(
        "--admin-password",
        help="deprecated: visible to every local user in the process list; use "
        "--admin-password-file or $MODD_ADMIN_PASSWORD",
    )
    p.add_argument(
        "--allowed-host",
        action="append",
        default=[],
        metavar="NAME",
        help="a Host name clients may use besides the loopback names (repeat)",
    )
    p.add_argument(
        "--trusted-proxy",
        action="append",
        metavar="ADDRESS",
        default=[a for a in os.environ.get("MODD_TRUSTED_PROXIES", "").split() if a],
        help="address of a reverse proxy whose X-Forwarded-For/-Proto headers are "
        "believed (repeat; default $MODD_TRUSTED_PROXIES; none: they are ignored)",
    )
    p.add_argument(
        "--tile-origin",
        action="append",
        metavar="ORIGIN",
        default=[o for o in os.environ.get("MODD_TILE_ORIGINS", "").split() if o],
        help="an origin (https://host[:port]) the map may load tiles from (repeat; "
        "default $MODD_TILE_ORIGINS, space-separated; none: no foreign images)",
    )
    p.add_argument(
        "--tiles",
        type=Path,
        metavar="DIR",
        default=os.environ.get("MODD_TILES") or None,
        help="a folder of map tiles laid out <z>/<x>/<y>.png, served to the Map at "
        "/api/tiles (a basemap offline; default $MODD_TILES; none: no tiles served)",
    )
    p.add_argument(
        "--viewer-origin",
        action="append",
        metavar="ORIGIN",
        default=[o for o in os.environ.get("MODD_VIEWER_ORIGINS", "").split() if o],
        help="the origin (https://host[:port]) of a web viewer allowed to open the "
        "WebSockets, e.g. a Lichtblick web app (repeat; default "
        "$MODD_VIEWER_ORIGINS; docs/ecosystem.md)",
    )
    a = p.parse_args(argv)
    for option, origins in (("--tile-origin", a.tile_origin), ("--viewer-origin", a.viewer_origin)):
        for origin in origins:
            try:
                check_origin(origin)
            except ValueError as exc:
                p.error(f"{option}: {exc}")
    password = os.environ.get("MODD_ADMIN_PASSWORD")
    if a.admin_password_file is not None:
        try:  # a small regular file (not /dev/zero, not a link), like every secret
            password = read_secret(a.admin_password_file, "admin password file").splitlines()[0]
        except (OSError, ValueError, IndexError) as exc:
            p.error(
                f"--admin-password-file {a.admin_password_file}: cannot read a password "
                f"({exc or 'empty file'})"
            )
    if (
        a.database_url
        and a.database_url != os.environ.get("MODD_DATABASE_URL")
        and _has_password(a.database_url)
    ):
        print(
            "modd-backend: warning: --database-url shows the database password to every "
            "local user (process list); use $MODD_DATABASE_URL",
            file=sys.stderr,
        )
    if a.admin_password is not None:
        print(
            "modd-backend: warning: --admin-password shows the password to every local "
            "user (process list); use --admin-password-file or $MODD_ADMIN_PASSWORD",
            file=sys.stderr,
        )
        password = a.admin_password
    return Settings(
        data_dir=a.data,
        database_url=a.database_url,
        host=a.host,
        port=a.port,
        zenoh_connect=tuple(a.zenoh_connect) if a.zenoh_connect else DEFAULT_ZENOH_CONNECT,
        zenoh_listen=tuple(a.zenoh_listen),
        zenoh_enabled=not a.no_zenoh,
        frontend_dist=a.frontend,
        archive_dir=a.archives,
        record_dir=a.records,
        deploy_timeout_s=a.deploy_timeout,
        initial_admin_password=password,
        allowed_hosts=tuple(a.allowed_host),
        trusted_proxies=tuple(a.trusted_proxy),
        tile_origins=tuple(a.tile_origin),
        tile_dir=Path(a.tiles).absolute() if a.tiles else None,
        cors_origins=tuple(a.viewer_origin),
        preload_milp=True,
        store_processes=a.store_processes,
        scene_port=None if a.scene_port < 0 else a.scene_port,
        foxglove_port=a.foxglove_port,
        foxglove_replay_port=a.foxglove_replay_port,
        zenoh_credentials=Path(a.zenoh_credentials) if a.zenoh_credentials else None,
        deploy_key_file=Path(a.deploy_key) if a.deploy_key else None,
        link_keys_dir=a.link_keys.absolute() if a.link_keys else None,
        pairing_key_file=a.pairing_key.absolute() if a.pairing_key else None,
    )


def _store_processes(text: str) -> int:
    """0..16 (argparse reports anything else, $MODD_STORE_PROCESSES included)."""
    try:
        n = int(text)
    except ValueError:
        n = -1
    if not 0 <= n <= MAX_STORE_PROCESSES:
        raise argparse.ArgumentTypeError(f"{text!r} is not a count 0..{MAX_STORE_PROCESSES}")
    return n


def _is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class RedactQuery(logging.Filter):
    """Cuts the query string from every logged request target (access and
    WebSocket lines; a path, or an absolute-form target ``ws://host/p?q``),
    so no secret sent in a URL ends up in a log.

    >>> r = logging.LogRecord("a", 20, "", 0, "%s %s", ("ws://h/foxglove/live?ticket=T", 1), None)
    >>> RedactQuery().filter(r), r.args
    (True, ('ws://h/foxglove/live?…', 1))
    """

    def filter(self, record: logging.LogRecord) -> bool:
        if isinstance(record.args, tuple):
            record.args = tuple(
                a.split("?", 1)[0] + "?…" if isinstance(a, str) and _target(a) else a
                for a in record.args
            )
        return True


def _target(arg: str) -> bool:
    """A request target with a query: a path, or a URL (absolute form)."""
    return "?" in arg and (arg.startswith("/") or "://" in arg.split("?", 1)[0])


def log_config() -> dict[str, Any]:
    from uvicorn.config import LOGGING_CONFIG

    cfg = copy.deepcopy(LOGGING_CONFIG)
    cfg["filters"] = {"redact": {"()": RedactQuery}}
    for handler in cfg["handlers"].values():
        handler["filters"] = ["redact"]
        # written by a thread of their own, off the event loop (logqueue.py)
        handler["class"] = "modd_backend.logqueue.QueuedStreamHandler"
    return cfg


def main(argv: list[str] | None = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if args and args[0] in ("backup", "restore"):
        from .backup import main as backup_main

        return backup_main(args)
    import uvicorn

    from .app import create_app

    settings = parse_args(argv)
    if not _is_loopback(settings.host):
        print(f"modd-backend: warning: listening on {settings.host}, not loopback", file=sys.stderr)
    uvicorn.run(
        create_app(settings),
        host=settings.host,
        port=settings.port,
        log_level="info",
        **server_options(settings),
    )
    return 0


def server_options(settings: Settings) -> dict[str, Any]:
    """uvicorn's options for this service. X-Forwarded-* headers are read only
    from ``trusted_proxies`` (uvicorn believes them from 127.0.0.1 by default,
    so any local process could pose as any client address)."""
    from .coalesce import CoalescingHttpToolsProtocol
    from .wspacing import PacedWebSocketProtocol

    proxies = list(settings.trusted_proxies)
    return {
        # an answer's headers and body in one send (coalesce.py, issue 41)
        "http": CoalescingHttpToolsProtocol,
        "log_config": log_config(),
        "ws_max_size": 1024 * 1024,
        # live values are small JSON: compressing them cost the event loop more
        # than it saved on loopback and LAN links (issue 41)
        "ws_per_message_deflate": False,
        "ws": PacedWebSocketProtocol,
        "proxy_headers": bool(proxies),
        "forwarded_allow_ips": proxies or None,
    }


if __name__ == "__main__":
    raise SystemExit(main())
