"""Typed settings, passed to :func:`create_app`; nothing is read at import time.

>>> s = Settings(data_dir=Path("/tmp/modd"))
>>> s.effective_database_url
'sqlite:////tmp/modd/modd.sqlite3'
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

#: zenoh endpoint of the SubBroker in the embedded default (docs/backend.md).
DEFAULT_ZENOH_CONNECT = ("tcp/127.0.0.1:7447",)


#: A Host header: a name or a bracketed IPv6 address, then at most a port.
_HOST = re.compile(r"(?:\[(?P<v6>[0-9a-f:.]+)\]|(?P<name>[a-z0-9_.-]+))(?::[0-9]{1,5})?")
_ORIGIN = re.compile(
    r"https?://[A-Za-z0-9.-]+(:[0-9]{1,5})?|https?://\[[0-9A-Fa-f:.]+\](:[0-9]{1,5})?"
)


def check_origin(origin: str) -> str:
    """``origin`` if it is an http(s) origin with no path, else ValueError naming it.

    >>> check_origin("https://tile.openstreetmap.org")
    'https://tile.openstreetmap.org'
    """
    if not _ORIGIN.fullmatch(origin):
        raise ValueError(
            f"tile origin {origin!r}: expected scheme://host[:port] "
            "(http or https, no path), e.g. https://tile.openstreetmap.org"
        )
    return origin


@dataclass(frozen=True)
class Settings:
    """Everything the service is configured with.

    ``database_url`` overrides the SQLite file under ``data_dir`` (e.g.
    ``postgresql+psycopg://user:pw@127.0.0.1/modd``). ``archive_dir`` holds one
    folder of MCAP files per drone (``<archive_dir>/<drone>/*.mcap``).
    ``initial_admin_password`` is for scripted set-ups and tests; when None the
    first start draws one and prints it once.
    """

    data_dir: Path
    database_url: str | None = None
    host: str = "127.0.0.1"
    port: int = 8000
    zenoh_connect: tuple[str, ...] = DEFAULT_ZENOH_CONNECT
    zenoh_listen: tuple[str, ...] = ()
    zenoh_enabled: bool = True
    frontend_dist: Path | None = None
    archive_dir: Path | None = None
    record_dir: Path | None = None  # the SubBrokers' base-station records, <record_dir>/<drone>/
    deploy_timeout_s: float = 10.0
    subscribe_timeout_s: float = 3.0
    stream_queue_size: int = 256
    token_ttl_s: int = 12 * 3600
    initial_admin_password: str | None = None
    preload_milp: bool = False
    #: Port of the viser 3D scene on ``host``; None: no scene, 0: any free port.
    scene_port: int | None = None
    #: Loopback port of the Foxglove live server (TLS; viewers come in through
    #: ``/foxglove/live``: routers/foxglove.py, docs/ecosystem.md); 0: none.
    foxglove_port: int = 0
    #: Loopback port of the Foxglove replay of an archive the user picks (through
    #: ``/foxglove/replay``); 0: none.
    foxglove_replay_port: int = 0
    cors_origins: tuple[str, ...] = field(default_factory=tuple)
    #: Origins (scheme://host[:port]) the map may load tiles from; none by default,
    #: so the workbench loads no image from elsewhere (docs/security.md).
    tile_origins: tuple[str, ...] = field(default_factory=tuple)
    #: A folder of map tiles (``<z>/<x>/<y>.png``) served at ``/api/tiles``: a basemap
    #: offline, from the workbench's own origin; None: no tiles served.
    tile_dir: Path | None = None
    #: The ``backend`` identity's zenoh user:password file (docs/security.md).
    zenoh_credentials: Path | None = None
    #: The key that signs deploys, shared with the SubBroker (its deploy.key).
    deploy_key_file: Path | None = None
    #: The base station's Ed25519 key that signs pairing bundles (made at first use);
    #: None: ``<data_dir>/pairing/station.key`` (modd_backend/pairing.py).
    pairing_key_file: Path | None = None
    #: The drones' link keys, ``<drone>.key`` (made when a drone is first paired; each
    #: SubBroker reads its own); None: ``<data_dir>/pairing/link-keys``.
    link_keys_dir: Path | None = None
    #: Host names (or host:port) requests may name besides the loopback names
    #: (localhost, 127.0.0.1, ::1) and ``host``; "*" allows any (not advised).
    allowed_hosts: tuple[str, ...] = field(default_factory=tuple)
    #: Addresses of reverse proxies whose X-Forwarded-For/-Proto are believed.
    #: None by default: any local process could otherwise name any client
    #: address (and escape the per-address login throttling).
    trusted_proxies: tuple[str, ...] = field(default_factory=tuple)
    #: Failed logins allowed per account / per client address within the window.
    login_limit_account: int = 10
    login_limit_address: int = 50
    login_window_s: float = 300.0
    #: An account that logged in from an address within this time (in this
    #: process) is past that address's lock; 0: never (the address lock is for all).
    login_known_s: float = 30 * 86_400.0
    #: Largest request body any route accepts (413 beyond), and JSON nesting depth (422).
    max_body_bytes: int = 4 * 1024 * 1024
    max_json_depth: int = 64
    #: Threads of their own for login: never queued behind the worker threads
    #: that run the other sync routes (saves, reads).
    login_threads: int = 2
    #: Processes running the hot routes' store work (a model's read and save,
    #: its versions: storeproc.py), so its Python never holds the event loop's
    #: interpreter lock; 0: threads of this process. 2 in the CLI.
    store_processes: int = 0
    #: Heavy routes (CSV export, series, deploy): at once per user and in all.
    heavy_per_user: int = 2
    heavy_total: int = 8
    #: Live subscriptions per WebSocket and per user (over all their sockets).
    ws_subscriptions_per_socket: int = 256
    ws_subscriptions_per_user: int = 1024
    #: Open WebSockets (streams, 3D scene, Foxglove) per user and per client
    #: address (all loopback addresses are one); beyond: closed with 4429.
    ws_sockets_per_user: int = 64
    ws_sockets_per_address: int = 512
    #: Stream sockets accepted but not yet authenticated (waiting for their
    #: first message) per client address, and how long one may wait; beyond
    #: the cap a socket is refused before it is accepted (HTTP 403), past the
    #: wait closed with 4401. A cookie session is checked before the accept.
    ws_unauthenticated_per_address: int = 32
    ws_auth_timeout_s: float = 5.0
    #: How often an open WebSocket re-checks its session and roles (seconds).
    ws_recheck_s: float = 0.4

    def __post_init__(self) -> None:
        for origin in self.tile_origins:
            check_origin(origin)

    def host_allowed(self, host_header: str) -> bool:
        """Whether a request's ``Host`` names this service (DNS rebinding guard)."""
        if "*" in self.allowed_hosts:
            return True
        host = host_header.strip().lower()
        parts = _HOST.fullmatch(host)  # a name or [address], then at most a port
        if parts is None:
            return False
        name = parts["v6"] or parts["name"]
        names = {"localhost", "127.0.0.1", "::1", self.host.lower()}
        names |= {h.lower() for h in self.allowed_hosts}
        return name in names or host in names or name.endswith(".localhost")

    @property
    def effective_database_url(self) -> str:
        if self.database_url:
            return self.database_url
        return f"sqlite:///{(self.data_dir / 'modd.sqlite3').as_posix()}"

    @property
    def effective_record_dir(self) -> Path:
        return self.record_dir if self.record_dir is not None else self.data_dir / "records"

    @property
    def effective_pairing_key(self) -> Path:
        return self.pairing_key_file or self.data_dir / "pairing" / "station.key"

    @property
    def effective_link_keys(self) -> Path:
        return self.link_keys_dir or self.data_dir / "pairing" / "link-keys"

    @property
    def effective_archive_dir(self) -> Path:
        return self.archive_dir if self.archive_dir is not None else self.data_dir / "archives"
