"""Who may do what on a SubBroker's zenoh keys (docs/security.md, "Zenoh"):
the identities, their credentials files and the ``access_control`` rules.

Three identities, least privilege, per drone:

- ``subbroker``: puts values (``modd/<drone>/sub/**``) and status, serves the
  ``deploy`` and ``subscribe`` queryables;
- ``backend``: queries ``deploy``, ``subscribe`` and ``backfill`` and reads values and status;
- ``viewer``: reads values and status, nothing else.

A credentials directory (0700) holds ``users`` (the router's dictionary,
``user:password`` lines), one ``<identity>.cred`` per identity (one
``user:password`` line, what a client gives) and ``deploy.key`` (the HMAC key
that signs deploys). Every file is 0600 and made at first start;
nothing here prints a password.

>>> sorted(acl("usv")["policies"][0]["subjects"])
['subbroker']
"""

from __future__ import annotations

import json
import logging
import os
import secrets
import stat
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from modd_contracts import keys

log = logging.getLogger("modd.zenoh")

IDENTITIES = ("subbroker", "backend", "viewer")
#: The identity base stations give each other in a router mesh (docs/fleet.md), made
#: only for a station that meshes (``CredentialStore.ensure_station``).
STATION_IDENTITY = "station"
DICTIONARY = "users"
DEPLOY_KEY = "deploy.key"
#: When each credential file was last made anew after the first start (file name -> UTC ISO
#: time): what the backend's Downloads panel announces (``remade_notes``).
REMADE = "remade.json"
_MAX_REMADE_BYTES = 16 * 1024
#: Key and credentials files are small; anything bigger is a mistake or an attack.
MAX_SECRET_BYTES = 64 * 1024


@dataclass(frozen=True)
class Credentials:
    """A zenoh user name and password (``repr`` hides the password)."""

    user: str
    password: str

    def __repr__(self) -> str:
        return f"Credentials(user={self.user!r}, password=<hidden>)"


def read_secret(path: str | Path, what: str = "secret") -> bytes:
    """The bytes of a key or credentials file: a regular file of at most
    MAX_SECRET_BYTES, read without following a final symlink; one trailing
    newline stripped. ValueError naming the file otherwise; a warning when
    group or others may read it."""
    path = Path(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NOFOLLOW | getattr(os, "O_NONBLOCK", 0))
    except OSError as exc:
        raise ValueError(f"{what} file {path}: {exc.strerror}") from exc
    try:
        st = os.fstat(fd)
        if not stat.S_ISREG(st.st_mode):
            raise ValueError(f"{what} file {path}: not a regular file")
        if st.st_size > MAX_SECRET_BYTES:
            raise ValueError(
                f"{what} file {path}: {st.st_size} bytes, more than {MAX_SECRET_BYTES}"
            )
        if st.st_mode & 0o077:
            log.warning(
                "%s file %s can be read by group or others (mode %o): chmod 600 it",
                what,
                path,
                stat.S_IMODE(st.st_mode),
            )
        data = os.read(fd, MAX_SECRET_BYTES + 1)
    finally:
        os.close(fd)
    if len(data) > MAX_SECRET_BYTES:
        raise ValueError(f"{what} file {path}: more than {MAX_SECRET_BYTES} bytes")
    data = data[:-1] if data.endswith(b"\n") else data
    if not data:
        raise ValueError(f"{what} file {path}: the file is empty")
    return data


def read_credentials(path: str | Path) -> Credentials:
    """A ``.cred`` file: one ``user:password`` line."""
    text = read_secret(path, "zenoh credentials").decode("utf-8", "replace").strip()
    user, sep, password = text.partition(":")
    if not sep or not user or not password or "\n" in text:
        raise ValueError(f"zenoh credentials file {path}: expected one line user:password")
    return Credentials(user, password)


def _write_private(path: Path, data: bytes) -> None:
    """Create ``path`` 0600 (never through a symlink, never over a file)."""
    flags = os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW
    fd = os.open(path, flags, 0o600)
    try:
        os.write(fd, data)
    finally:
        os.close(fd)


def private_dir(path: Path) -> Path:
    """``path`` made (0700) or checked: a real directory, owned by this user,
    not reached through a symlink; ValueError otherwise."""
    try:
        path.mkdir(mode=0o700, parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"{path}: {exc.strerror}") from exc
    st = path.lstat()
    if stat.S_ISLNK(st.st_mode) or not stat.S_ISDIR(st.st_mode):
        raise ValueError(f"{path}: a symbolic link or not a directory; refusing to use it")
    if st.st_uid != os.getuid():
        raise ValueError(f"{path}: owned by uid {st.st_uid}, not by this user; refusing to use it")
    if st.st_mode & 0o077:
        os.chmod(path, 0o700)
    return path


class CredentialStore:
    """The credentials directory of one deployment (a SubBroker's, `modd up`'s)."""

    def __init__(self, directory: str | Path) -> None:
        self.dir = Path(directory)
        self.remade: list[str] = []  # files made anew after a first start (see ensure)

    def ensure(self) -> CredentialStore:
        """Make the directory and every missing file (first start); idempotent.
        A file missing after the first start (deleted by hand) is made anew with a
        new secret, named in ``remade`` and logged as a warning: copies of it that
        were handed out no longer work, and whoever holds one must be told."""
        private_dir(self.dir)
        first = not self.dictionary.exists()
        made = []
        for ident in IDENTITIES:
            cred = self.dir / f"{ident}.cred"
            if not cred.exists():
                _write_private(cred, f"{ident}:{secrets.token_urlsafe(24)}\n".encode())
                made.append(cred.name)
        key = self.dir / DEPLOY_KEY
        if not key.exists():
            _write_private(key, (secrets.token_hex(32) + "\n").encode())
            made.append(key.name)
        self._write_dictionary()
        if made and first:
            log.info("zenoh credentials made in %s: %s", self.dir, ", ".join(made))
        elif made:
            self.remade = made
            self._note_remade(made)
            log.warning(
                "zenoh credentials missing from %s were made anew with new secrets: %s; "
                "copies handed out before no longer work",
                self.dir,
                ", ".join(made),
            )
        return self

    def _note_remade(self, made: list[str]) -> None:
        from datetime import UTC, datetime

        now = datetime.now(UTC).isoformat(timespec="seconds").replace("+00:00", "Z")
        notes = {**remade_notes(self.dir), **dict.fromkeys(made, now)}
        tmp = self.dir / f".{REMADE}.{secrets.token_hex(4)}"
        _write_private(tmp, (json.dumps(notes, sort_keys=True) + "\n").encode())
        tmp.replace(self.dir / REMADE)

    def ensure_station(self) -> CredentialStore:
        """The ``station`` identity of a station in a router mesh (docs/fleet.md): made
        when missing (the first station), else the copy the campaign handed over; it
        joins the dictionary, so the other stations' routers are let in."""
        self.ensure()
        cred = self.cred_file(STATION_IDENTITY)
        if not cred.exists():
            _write_private(cred, f"{STATION_IDENTITY}:{secrets.token_urlsafe(24)}\n".encode())
            log.info("zenoh station credentials made: %s (copy it to every station)", cred)
        self._write_dictionary()
        return self

    def _identities(self) -> tuple[str, ...]:
        extra = (STATION_IDENTITY,) if self.cred_file(STATION_IDENTITY).exists() else ()
        return IDENTITIES + extra

    def _write_dictionary(self) -> None:
        lines = [f"{c.user}:{c.password}\n" for c in map(self.credentials, self._identities())]
        data = "".join(lines).encode()
        path = self.dictionary
        if path.exists() and read_secret(path, "zenoh dictionary") + b"\n" == data:
            return
        tmp = path.with_name(f".{DICTIONARY}.{secrets.token_hex(4)}")
        _write_private(tmp, data)
        tmp.replace(path)

    @property
    def dictionary(self) -> Path:
        return self.dir / DICTIONARY

    def cred_file(self, identity: str) -> Path:
        return self.dir / f"{identity}.cred"

    def credentials(self, identity: str) -> Credentials:
        return read_credentials(self.cred_file(identity))

    @property
    def deploy_key_file(self) -> Path:
        return self.dir / DEPLOY_KEY

    def deploy_key(self) -> bytes:
        return read_secret(self.deploy_key_file, "deploy key")


def _rule(rid: str, messages: list[str], flows: list[str], keys: list[str]) -> dict[str, Any]:
    return {
        "id": rid,
        "messages": messages,
        "flows": flows,
        "permission": "allow",
        "key_exprs": keys,
    }


def acl(drone: str | None = None) -> dict[str, Any]:
    """The ``access_control`` object of the router every client of ``drone``
    goes through (``None``: every drone, ``modd/*``). Default deny; rules per
    key expression, message type and flow (ingress: from that client into the
    router; egress: from the router to it). A subscriber also needs
    ``declare_subscriber`` on egress, else its publisher never learns of it."""
    own = [keys.values_tree(drone or None), keys.status_key(drone or None)]
    queries = keys.queryables_of(drone or None)
    # readers may subscribe across drones (modd/*/sub/*): reading is not writing
    read = [keys.values_tree(None), keys.ALL_STATUS]
    rules = [
        # the SubBroker: its values and status, its queryables (when it is a client)
        _rule(
            "subbroker_out",
            ["put", "delete", "declare_queryable", "reply"],
            ["ingress"],
            [*own, *queries],
        ),
        _rule(
            "subbroker_in",
            ["declare_subscriber", "query", "declare_queryable"],
            ["egress"],
            [*read, *queries],
        ),
        # the SubBroker: the liveliness tokens electing the station serving its drone,
        # the window records, and the datagrams a standby station's modem heard
        _rule(
            "subbroker_fleet",
            [
                "put",
                "declare_subscriber",
                "liveliness_token",
                "declare_liveliness_subscriber",
                "liveliness_query",
                "declare_queryable",
                "query",
                "reply",
            ],
            ["ingress", "egress"],
            [keys.fleet_tree(drone or None)],
        ),
        # the SubBroker of a station in a mesh hears its drone's values another serves
        _rule(
            "subbroker_hear",
            ["declare_subscriber", "put"],
            ["ingress", "egress"],
            [keys.values_tree(drone or None)],
        ),
        # zenoh's recovery of delivered values (modd.zenoh_recovery): the SubBroker's
        # advanced publishers (numbers, cache, heartbeats) ...
        _rule(
            "adv_publish",
            [
                "put",
                "declare_subscriber",
                "declare_queryable",
                "query",
                "reply",
                "liveliness_token",
                "declare_liveliness_subscriber",
                "liveliness_query",
            ],
            ["ingress", "egress"],
            [keys.recovery_tree(drone or None)],
        ),
        # ... and the readers' advanced subscribers, which ask a publisher's cache and
        # hear its heartbeats; no reader answers for a publisher (no queryable, no reply)
        _rule(
            "adv_read",
            [
                "put",
                "declare_subscriber",
                "query",
                "liveliness_token",
                "declare_liveliness_subscriber",
                "liveliness_query",
            ],
            ["ingress", "egress"],
            [keys.recovery_tree(None)],
        ),
        # a cache's answers carry the values' own keys
        _rule(
            "adv_answered",
            ["reply"],
            ["egress"],
            [keys.recovery_tree(None), keys.values_tree(None)],
        ),
        # readers (backend and viewers): subscribe to values and status; a
        # subscription may be as wide as modd/**, only these keys' puts reach it
        _rule("read_in", ["declare_subscriber"], ["ingress", "egress"], [keys.EVERYTHING]),
        _rule("read_out", ["put", "delete"], ["egress"], read),
        # the backend alone asks the queryables
        _rule("ask", ["query"], ["ingress"], queries),
        _rule("answer", ["reply", "declare_queryable"], ["egress"], queries),
    ]
    subjects = [{"id": ident, "usernames": [ident]} for ident in IDENTITIES]
    policies = [
        {
            "id": "subbroker",
            "rules": [
                "subbroker_out",
                "subbroker_in",
                "subbroker_fleet",
                "subbroker_hear",
                "adv_publish",
            ],
            "subjects": ["subbroker"],
        },
        {
            "id": "backend",
            "rules": ["read_in", "read_out", "ask", "answer", "adv_read", "adv_answered"],
            "subjects": ["backend"],
        },
        {
            "id": "viewer",
            "rules": ["read_in", "read_out", "adv_read", "adv_answered"],
            "subjects": ["viewer"],
        },
    ]
    return {
        "enabled": True,
        "default_permission": "deny",
        "rules": rules,
        "subjects": subjects,
        "policies": policies,
    }


def remade_notes(directory: str | Path) -> dict[str, str]:
    """The credential files of ``directory`` made anew after its first start,
    with when (UTC, ISO 8601): ``{}`` when none was, or the note is unreadable.

    >>> remade_notes("/nonexistent")
    {}
    """
    path = Path(directory) / REMADE
    known = {f"{i}.cred" for i in IDENTITIES} | {DEPLOY_KEY}
    try:
        if path.stat().st_size > _MAX_REMADE_BYTES:
            return {}
        raw = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    if not isinstance(raw, dict):
        return {}
    return {k: v for k, v in raw.items() if k in known and isinstance(v, str) and len(v) <= 40}
