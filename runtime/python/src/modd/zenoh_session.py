"""Zenoh sessions for MoDD processes, with the embedded defaults of
docs/subbroker.md: multicast scouting off, ``scouting/delay`` 0, loopback
endpoints, and the credentials plumbing of docs/security.md: a listening
session authenticates its clients (``dictionary_file``) and applies
``access_control``; a connecting session gives its user name and password
(``credentials``, a :class:`~modd.zenoh_auth.Credentials`). TLS passes through
as raw zenoh settings (``extra``).

>>> s = ZenohSettings(listen=("tcp/127.0.0.1:7447",))
>>> s.inserts()["scouting/multicast/enabled"]
'false'
"""

from __future__ import annotations

import argparse
import json
import os
import socket
import time
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .zenoh_auth import Credentials, CredentialStore, acl, read_credentials
from .zenoh_gate_policy import REFUSAL_MARK, GateLimits
from .zenoh_mesh import STATION, Mesh, station_acl

if TYPE_CHECKING:
    import zenoh

#: Where a SubBroker listens by default, and where clients connect by default.
DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
MODES = ("peer", "client", "router")
RECONNECT = "{period_init_ms: 100, period_max_ms: 1000, period_increase_factor: 2}"
#: How long a client keeps trying a router that closes every new connection at once (its
#: ``accept_pending`` reached: a flood of connections that never authenticate).
BUSY_WAIT_S = 10.0
#: Tries whose probe found the router waiting for a handshake before a failure is put
#: down to the credentials (a router shedding a flood has room again now and then).
HELD_TRIES = 3
#: Seconds a failed open takes past which it was no refusal (a router refuses credentials
#: within a round trip) but a router too busy to finish the handshake.
SLOW_OPEN_S = 1.0
#: A listening session's bounds against connections that open and never authenticate
#: (docs/security.md, "Idle connections"): zenoh's defaults (10 s to authenticate, 100 at
#: once) let 100 idle sockets lock every new session out for 10 s. Each is overridable in
#: ``[zenoh.settings]`` (or a ``config_file`` that sets it).
LISTENER_LIMITS = {
    # ms a connection may take from accept to an authenticated session (default 10000)
    "transport/unicast/accept_timeout": "2000",
    # connections authenticating at once (default 100); more are closed at once
    "transport/unicast/accept_pending": "2000",
    # authenticated sessions at once (default 1000): the backend, tools and viewers
    "transport/unicast/max_sessions": "256",
    # links per session (zenoh's default, kept explicit)
    "transport/unicast/max_links": "1",
}


@dataclass(frozen=True)
class ZenohSettings:
    """How to open a zenoh session.

    ``extra`` maps zenoh configuration paths to JSON5 values inserted last
    (e.g. ``{"transport/link/tls/root_ca_certificate": '"ca.pem"'}``);
    ``config_file`` is a full zenoh JSON5 configuration to start from.
    ``credentials``: what this session gives when it connects;
    ``dictionary_file``: the ``user:password`` lines it accepts from those that
    connect to it; ``access_control``: their rules (:func:`modd.zenoh_auth.acl`).
    ``credentials_dir`` (SubBroker config) is where a SubBroker keeps them.
    """

    mode: str = "peer"
    listen: tuple[str, ...] = ()
    connect: tuple[str, ...] = ()
    config_file: str | None = None
    extra: Mapping[str, str] = field(default_factory=dict)
    credentials: Credentials | None = None
    dictionary_file: str | None = None
    access_control: Mapping[str, Any] | None = None
    credentials_dir: str | None = None
    #: The per-source bounds of the accept gate in front of a SubBroker's listener
    #: (``[zenoh.gate]``; :mod:`modd.zenoh_gate`).
    gate: GateLimits = field(default_factory=GateLimits)
    #: The other base stations' routers this one joins (``[zenoh.mesh]``; docs/fleet.md).
    mesh: Mesh | None = None

    def __post_init__(self) -> None:
        if self.mode not in MODES:
            raise ValueError(f"zenoh mode {self.mode!r}: expected one of {', '.join(MODES)}")

    def inserts(self) -> dict[str, str]:
        """Configuration path -> JSON5 value, in the order they are applied."""
        out = {
            "mode": json.dumps(self.mode),
            "scouting/multicast/enabled": "false",
            "scouting/delay": "0",
        }
        if self.listen or self.mode != "client":
            out["listen/endpoints"] = json.dumps(list(self.listen))
        if self.listen:
            out.update(LISTENER_LIMITS)
        connect = self.connect + (self.mesh.endpoints() if self.mesh else ())
        if self.mesh is not None:
            out.update(self.mesh.inserts())
        if connect:
            out["connect/endpoints"] = json.dumps(list(connect))
            # come back within a second when the other side restarts
            out["connect/retry"] = RECONNECT
            if self.mode == "client":
                # open even when the router is not up yet, and connect when it is
                out["connect/exit_on_failure"] = "{client: false}"
                out["connect/timeout_ms"] = "{client: 0}"
        if self.credentials is not None:
            out["transport/auth/usrpwd/user"] = json.dumps(self.credentials.user)
            out["transport/auth/usrpwd/password"] = json.dumps(self.credentials.password)
        if self.dictionary_file is not None:
            out["transport/auth/usrpwd/dictionary_file"] = json.dumps(self.dictionary_file)
        if self.access_control is not None:
            out["access_control"] = json.dumps(self.access_control)
        out.update(self.extra)
        return out

    @classmethod
    def from_mapping(cls, data: Mapping[str, Any], where: str = "zenoh") -> ZenohSettings:
        """From a config-file table (docs/subbroker.md, ``[zenoh]``)."""
        known = {
            "mode",
            "listen",
            "connect",
            "config_file",
            "settings",
            "credentials_dir",
            "gate",
            "mesh",
        }
        unknown = sorted(set(data) - known)
        if unknown:
            listing = ", ".join(sorted(known))
            raise ValueError(f"{where}: unknown key {unknown[0]!r}; known: {listing}")
        extra = data.get("settings", {})
        if not isinstance(extra, Mapping):
            raise ValueError(f"{where}.settings: expected a table of path = value")
        gate = data.get("gate", {})
        if not isinstance(gate, Mapping):
            raise ValueError(f"{where}.gate: expected a table (docs/subbroker.md)")
        mesh = data.get("mesh")
        if mesh is not None and not isinstance(mesh, Mapping):
            raise ValueError(f"{where}.mesh: expected a table (docs/fleet.md)")
        return cls(
            mode=str(data.get("mode", "router")),
            listen=tuple(_str_list(data.get("listen", [DEFAULT_ENDPOINT]), f"{where}.listen")),
            connect=tuple(_str_list(data.get("connect", []), f"{where}.connect")),
            config_file=data.get("config_file"),
            extra={k: json.dumps(v) for k, v in extra.items()},  # TOML values -> JSON
            credentials_dir=str(data["credentials_dir"]) if "credentials_dir" in data else None,
            gate=GateLimits.from_mapping(gate, f"{where}.gate"),
            mesh=Mesh.from_mapping(mesh, f"{where}.mesh") if mesh is not None else None,
        )


def _str_list(value: Any, where: str) -> list[str]:
    if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
        raise ValueError(f"{where}: expected a list of endpoints such as {DEFAULT_ENDPOINT!r}")
    return list(value)


def add_viewer_args(p: argparse.ArgumentParser) -> None:
    """The options of a viewer of the SubBroker's zenoh (``modd-ros2``,
    ``modd-plotjuggler``): ``--modd-connect`` and ``--credentials``, as
    :func:`client_settings` takes them."""
    p.add_argument(
        "--modd-connect",
        default=os.environ.get("MODD_ZENOH_CONNECT", DEFAULT_ENDPOINT),
        metavar="ENDPOINT",
        help="the SubBroker's zenoh endpoint",
    )
    p.add_argument(
        "--credentials",
        metavar="FILE",
        help="a viewer's .cred file for the SubBroker's zenoh (default "
        "$MODD_ZENOH_CREDENTIALS; docs/security.md)",
    )


def client_settings(
    connect: str | None = None,
    credentials: Credentials | str | os.PathLike[str] | None = None,
) -> ZenohSettings:
    """Settings for a consumer on the base station: a client that listens
    nowhere and connects to the SubBroker or a router (``MODD_ZENOH_CONNECT``
    or :data:`DEFAULT_ENDPOINT` when ``connect`` is not given), with the user
    name and password of ``credentials`` (a ``.cred`` file, else
    ``$MODD_ZENOH_CREDENTIALS``; without any, the router refuses it)."""
    endpoint = connect or os.environ.get("MODD_ZENOH_CONNECT") or DEFAULT_ENDPOINT
    if credentials is None and os.environ.get("MODD_ZENOH_CREDENTIALS"):
        credentials = os.environ["MODD_ZENOH_CREDENTIALS"]
    if credentials is not None and not isinstance(credentials, Credentials):
        credentials = read_credentials(Path(credentials))
    return ZenohSettings(mode="client", connect=(endpoint,), credentials=credentials)


def secured(
    settings: ZenohSettings, store: CredentialStore, identity: str, drone: str | None
) -> ZenohSettings:
    """``settings`` with the credentials plumbing of ``store``: when it
    listens, it authenticates whoever connects (the store's dictionary) and
    applies :func:`~modd.zenoh_auth.acl` for ``drone``, gossip off (no peer
    learns another's address through it); when it connects, it gives
    ``identity``'s user name and password. Makes missing files (first start)."""
    store.ensure()
    extra = dict(settings.extra)
    changes: dict[str, Any] = {}
    if settings.listen:
        changes["dictionary_file"] = str(store.dictionary)
        changes["access_control"] = acl(drone)
        extra.setdefault("scouting/gossip/enabled", "false")
    if settings.connect:
        changes["credentials"] = store.credentials(identity)
    if settings.mesh is not None:  # a station's router: the others know it as `station`
        store.ensure_station()
        changes["dictionary_file"] = str(store.dictionary)
        changes["access_control"] = station_acl(acl(drone), settings.mesh.peer_ids())
        changes["credentials"] = store.credentials(STATION)
    return replace(settings, extra=extra, **changes)


def zenoh_config(settings: ZenohSettings) -> zenoh.Config:
    """A ``zenoh.Config`` for these settings."""
    import zenoh

    path = settings.config_file
    config = zenoh.Config.from_file(path) if path else zenoh.Config()
    inserts = settings.inserts()
    if path:  # a limit the file sets (not zenoh's default) is the file's
        default = zenoh.Config()
        for key in LISTENER_LIMITS:
            if key not in settings.extra and config.get_json(key) != default.get_json(key):
                inserts.pop(key, None)
    for key, value in inserts.items():
        try:
            config.insert_json5(key, value)
        except Exception as exc:  # zenoh raises ZError with the bare path
            shown = "<hidden>" if key.endswith("password") else value
            raise ValueError(f"zenoh setting {key} = {shown}: {exc}") from exc
    return config


def open_session(settings: ZenohSettings, busy_wait_s: float = BUSY_WAIT_S) -> zenoh.Session:
    """Open a session; raises ValueError naming the endpoints if it cannot,
    and, for a client the router turned away, why: the credentials it needs, or a
    router closing every new connection (it has as many in their handshake as it takes,
    ``accept_pending``), which is tried again for up to ``busy_wait_s``."""
    import zenoh

    if settings.listen:
        _room_for_pending()
    deadline = time.monotonic() + busy_wait_s
    pause, held = 0.1, 0
    while True:
        began = time.monotonic()
        try:
            return zenoh.open(zenoh_config(settings))
        except zenoh.ZError as exc:
            where = ", ".join(settings.listen + settings.connect) or "no endpoint"
            head = f"cannot open a zenoh session ({settings.mode}, {where})"
            if settings.mode != "client" or not settings.connect:
                raise ValueError(f"{head}: {exc}") from exc
            probe = tcp_probe(settings.connect[0])
            if probe == "held" and time.monotonic() - began >= SLOW_OPEN_S:
                probe = "slow"  # accepted, but no answer in time: not a refusal
            # "held" may be a router that shed this try (full) and has room again: a refusal
            # of the credentials is "held" every time, so it is said after HELD_TRIES
            held += probe == "held"
            busy = probe in ("closed", "slow") or is_gated(probe) or 0 < held < HELD_TRIES
            if not busy or time.monotonic() + pause > deadline:
                raise ValueError(f"{head}: {refusal(settings, probe, busy_wait_s)}") from exc
        time.sleep(pause)  # the router sheds connections that never authenticate
        pause = min(1.0, 2 * pause)


#: Where `make run` and `modd up` keep a viewer's credentials (docs/security.md).
CREDENTIALS_HINT = (
    "`make run` keeps a viewer's in data/credentials/viewer.cred "
    "(data-<port>/ with MODD_PORT), `modd up` in <workdir>/credentials/viewer.cred"
)


def refusal(settings: ZenohSettings, probe: str | None, waited_s: float = 0.0) -> str:
    """Why a client could not connect, in the user's words: ``probe`` is what the
    endpoint did with a new TCP connection (:func:`tcp_probe`; None: unknown).
    zenoh itself only says "Unable to connect" in every case.

    >>> refusal(ZenohSettings(mode="client", connect=("tcp/127.0.0.1:7447",)), "held")[:50]
    'the router at tcp/127.0.0.1:7447 needs credentials'
    """
    endpoint = settings.connect[0]
    if is_gated(probe):
        return (
            f"the SubBroker at {endpoint} refuses new connections from this address for now "
            f"(for {waited_s:g} s of tries): {probe}; your credentials were not checked. "
            "Something on this address opens connections without authenticating; try again "
            "later, or ask the base station's operator"
        )
    if probe == "slow":
        return (
            f"the router at {endpoint} takes connections but did not finish the handshake in "
            f"time (for {waited_s:g} s of tries): it is busy, likely with connections that "
            "never authenticate (transport/unicast/accept_pending); your credentials were "
            "not checked. Try again later, or ask the base station's operator (docs/security.md, "
            '"Connections per source")'
        )
    if probe == "none":
        return (
            f"nothing answers at {endpoint}: is the SubBroker running (`make run` or "
            "`modd up`), and is this its zenoh endpoint (--connect or $MODD_ZENOH_CONNECT)?"
        )
    if probe == "closed":
        return (
            f"the router at {endpoint} closes every new connection at once (for {waited_s:g} s "
            "of tries): it holds as many connections in their handshake as it takes "
            "(transport/unicast/accept_pending), so something is opening connections without "
            "authenticating; your credentials were not checked. Try again later, or ask the "
            'base station\'s operator (docs/security.md, "Idle connections")'
        )
    if settings.credentials is None:
        said = "needs credentials and none were given"
    else:
        said = f"refused the credentials of user {settings.credentials.user!r}"
    maybe = "" if probe == "held" else " (or nothing answers there)"
    return (
        f"the router at {endpoint} {said}{maybe}: give a credentials file with "
        f"--credentials FILE or $MODD_ZENOH_CREDENTIALS; {CREDENTIALS_HINT}"
    )


def tcp_probe(endpoint: str, timeout_s: float = 1.0, hold_s: float = 0.3) -> str | None:
    """What a ``tcp/host:port`` endpoint does with a new connection that says nothing:
    "none" (refused or unreachable), "closed" (accepted, then closed within ``hold_s``: a
    zenoh listener with as many connections in their handshake as it takes), "held"
    (kept open: a listener awaiting the handshake), the SubBroker's gate's reason when it
    turns this address away (:func:`is_gated`); None for another kind of endpoint."""
    kind, _, address = endpoint.partition("/")
    host, _, port = address.rpartition(":")
    if kind != "tcp" or not port.isdigit():
        return None
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout_s) as s:
            s.settimeout(hold_s)
            try:
                said = s.recv(512)
            except TimeoutError:
                return "held"
            except OSError:  # reset
                return "closed"
            if said.startswith(REFUSAL_MARK):
                return _gate_reason(said)
            return "closed" if not said else "held"
    except OSError:
        return "none"


#: How :func:`tcp_probe` starts the reason the SubBroker's gate gave.
GATED = "the gate says: "


def is_gated(probe: str | None) -> bool:
    return probe is not None and probe.startswith(GATED)


def _gate_reason(said: bytes) -> str:
    """The gate's one line, printable characters only (it comes from the network)."""
    text = said[len(REFUSAL_MARK) :].split(b"\n", 1)[0].decode("utf-8", "replace")
    return GATED + "".join(c if c.isprintable() else "?" for c in text)[:300]


def _room_for_pending() -> None:
    """Raises the soft limit on open files to what ``accept_pending`` may hold
    (a service's soft limit is often 1024), within the hard limit."""
    import resource

    # each pending connection: zenoh's socket, and the gate's two (modd.zenoh_gate)
    want = 3 * int(LISTENER_LIMITS["transport/unicast/accept_pending"]) + 1024
    soft, hard = resource.getrlimit(resource.RLIMIT_NOFILE)
    if soft != resource.RLIM_INFINITY and soft < want:
        new = want if hard == resource.RLIM_INFINITY else min(want, hard)
        resource.setrlimit(resource.RLIMIT_NOFILE, (new, hard))


def wait_connected(session: zenoh.Session, timeout_s: float = 5.0) -> bool:
    """Wait until the session sees a peer or a router (a get sent before that
    finds no queryable and returns nothing). True when connected."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        info = session.info
        if list(info.peers_zid()) or list(info.routers_zid()):
            return True
        time.sleep(0.01)
    return False
