"""Pairing bundles (docs/operations.md, "Pair"): what one drone needs from
this base station — its PubBroker configuration and model (the operator's
generated files) and its link key — sealed with a one-time code and signed
with the station's Ed25519 pairing key (``modd.pairing.bundle``).

The base station keeps, under the backend's data directory unless set:

- ``pairing/station.key``: the Ed25519 private key (0600), made at first use;
  its public key is pinned by every drone paired with it;
- ``pairing/link-keys/<drone>.key``: each drone's link key (0600), made when
  the drone is first paired; its SubBroker reads it (``[link] key =
  "file:.../<drone>.key"``).

>>> from pathlib import Path
>>> import tempfile
>>> d = Path(tempfile.mkdtemp())
>>> made = make_bundle({"drone": {"name": "usv"}}, d / "station.key", d / "keys",
...                    files=lambda model: {"pubbroker.json": {"link": {}}})
>>> made.drone, made.filename, (d / "keys" / "usv.key").stat().st_mode & 0o777 == 0o600
('usv', 'usv.modd-pair', True)
"""

from __future__ import annotations

import json
import logging
import os
import secrets
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey
from modd.pairing.bundle import SUFFIX, Verified, seal, verify
from modd.zenoh_auth import private_dir, read_secret
from modd_contracts.keys import check_name

log = logging.getLogger("modd_backend.pairing")

Files = Callable[[dict[str, Any]], dict[str, Any]]


@dataclass(frozen=True)
class Made:
    """A bundle just made: its bytes and the code shown once to the operator."""

    drone: str
    filename: str
    data: bytes
    code: str
    bundle: Verified
    link_key_file: Path


def _create_private(path: Path, data: bytes) -> None:
    private_dir(path.parent)
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    try:
        os.write(fd, data)
    finally:
        os.close(fd)


def station_key(path: Path) -> Ed25519PrivateKey:
    """The station's pairing key, made (0600) at first use."""
    if not path.exists():
        _create_private(path, Ed25519PrivateKey.generate().private_bytes_raw().hex().encode())
        log.info("pairing: made the base station's pairing key %s", path)
    raw = read_secret(path, "pairing key").decode("ascii", "replace").strip()
    try:
        return Ed25519PrivateKey.from_private_bytes(bytes.fromhex(raw))
    except ValueError:
        raise ValueError(f"pairing key file {path}: not a 32-byte Ed25519 key in hex") from None


def link_key(directory: Path, drone: str) -> tuple[Path, str]:
    """The drone's link key file and its text, made (0600, 32 random bytes in hex) if missing."""
    path = directory / f"{check_name('drone', drone)}.key"
    if not path.exists():
        _create_private(path, (secrets.token_hex(32) + "\n").encode())
        log.info("pairing: made the link key of drone %s in %s", drone, path)
    return path, read_secret(path, "link key").decode("ascii", "replace").strip()


def operator_files(model: dict[str, Any]) -> dict[str, Any]:
    """The drone's files from the operator's generated artefacts."""
    from modd_gen.generate import generate

    out: dict[str, Any] = {}
    for a in generate(model, "operator"):
        name = a.path.rpartition("/")[2]
        if name in ("pubbroker.json", "model.json"):
            out[name] = json.loads(a.content)
    return out


def make_bundle(
    model: dict[str, Any], key_file: Path, link_keys: Path, files: Files = operator_files
) -> Made:
    """A bundle for the model's drone; ValueError (said to the operator) when it cannot be."""
    drone = str(model["drone"]["name"])
    key_path, key_text = link_key(link_keys, drone)
    station = station_key(key_file)
    data, code = seal(station, drone, {**files(model), "link.key": key_text}, time.time_ns())
    return Made(drone, f"{drone}{SUFFIX}", data, code, verify(data), key_path)
