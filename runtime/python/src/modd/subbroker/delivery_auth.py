"""The delivery key and the handshake of TCP delivery (docs/subbroker.md): a
subscriber that asks for it (the generated C++ subscriber always does) opens
each connection with the challenge ``MODD-DELIVERY/1 <nonce hex>\\n``; the
SubBroker answers ``AUTH <hex HMAC-SHA256(key, "modd-delivery/1\\n" + nonce)>\\n``
before any value, so that a subscriber accepts values only from a holder of the
delivery key.

The key: the SubBroker's ``[delivery] key`` setting when given (``env:NAME`` or
``file:PATH``), else ``$MODD_DELIVERY_KEY`` when set (same forms), else
``$XDG_CONFIG_HOME/modd/delivery.key`` (default ``~/.config/modd/delivery.key``),
created with a random key, mode 0600, when absent. Both sides resolve it the
same way, so a SubBroker and the subscribers of the same user agree without
configuration; a subscriber on another host gets a copy of the file.

>>> proof(b"k", "00ff")
'45c7865d8ef3ee20259862288c9d952033919e01e0da9f998469d3607de8693b'
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
from pathlib import Path

GREETING = b"MODD-DELIVERY/1 "
LABEL = b"modd-delivery/1\n"
MAX_KEY_FILE = 4096


class DeliveryKeyError(RuntimeError):
    pass


def proof(key: bytes, nonce_hex: str) -> str:
    """The answer to a challenge: hex of HMAC-SHA256(key, LABEL + nonce)."""
    return hmac.new(key, LABEL + nonce_hex.encode("ascii"), hashlib.sha256).hexdigest()


def default_key_path() -> Path:
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "modd" / "delivery.key"


def _read_key_file(path: Path) -> bytes:
    try:
        # no final link; O_NONBLOCK: a FIFO planted as the key must not block the open
        fd = os.open(path, os.O_RDONLY | os.O_CLOEXEC | os.O_NOFOLLOW | os.O_NONBLOCK)
    except OSError as exc:
        raise DeliveryKeyError(f"delivery key file:{path}: {exc.strerror}") from exc
    with os.fdopen(fd, "rb") as f:
        st = os.fstat(f.fileno())
        if not stat.S_ISREG(st.st_mode) or st.st_size > MAX_KEY_FILE:
            raise DeliveryKeyError(
                f"delivery key file:{path}: not a regular file of at most {MAX_KEY_FILE} bytes"
            )
        data = f.read(MAX_KEY_FILE + 1)
    data = data[:-1] if data.endswith(b"\n") else data
    if not data:
        raise DeliveryKeyError(f"delivery key file:{path}: empty")
    return data


def _create_key_file(path: Path) -> None:
    """Write a random key into place atomically, unless a key is already there."""
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    tmp = path.with_name(f"{path.name}.tmp{os.getpid()}")
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o600)
    except FileExistsError:
        return
    with os.fdopen(fd, "w") as f:
        f.write(secrets.token_hex(32) + "\n")
    try:
        os.link(tmp, path)  # never replaces a key another process wrote first
    except FileExistsError:
        pass
    finally:
        tmp.unlink()


def check_ref(ref: str, where: str = "MODD_DELIVERY_KEY") -> str:
    """``ref`` when it is ``env:NAME`` or ``file:PATH`` (DeliveryKeyError otherwise)."""
    kind, _, name = ref.partition(":")
    if kind not in ("env", "file") or not name or any(c in name for c in "\n\r\0"):
        raise DeliveryKeyError(f"{where}: expected env:NAME or file:PATH, got {ref[:80]!r}")
    return ref


def load_key(ref: str = "") -> bytes:
    """The delivery key, resolved as described above (``ref``: the setting)."""
    where = "[delivery] key" if ref else "MODD_DELIVERY_KEY"
    ref = ref or os.environ.get("MODD_DELIVERY_KEY", "")
    if ref:
        kind, _, name = check_ref(ref, where).partition(":")
        if kind == "env":
            value = os.environ.get(name)
            if not value:
                raise DeliveryKeyError(f"delivery key {ref}: the variable is not set")
            return value.encode()
        return _read_key_file(Path(name))
    path = default_key_path()
    if not path.exists():
        _create_key_file(path)
    return _read_key_file(path)
