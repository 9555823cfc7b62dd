"""The pairing bundle (``<drone>.modd-pair``): what one drone needs from its
base station, encrypted with a one-time code and signed by the station.

The file is one line of canonical JSON (sorted keys, no spaces, ASCII):

- in the clear and signed: ``format``, ``version``, ``drone``, ``issued_ns``,
  ``expires_ns``, ``station`` (its Ed25519 public key and fingerprint),
  ``kdf`` (scrypt parameters and salt), ``aead`` (AES-256-GCM nonce);
- ``ciphertext``: the payload (the drone's files, the link key among them),
  AES-256-GCM under a key scrypt derives from the code, the clear fields as
  associated data;
- ``signature``: Ed25519 by the station over everything else.

A bundle is refused unless its bytes are exactly the canonical form of what
they parse to, so a byte flipped anywhere is found (a changed field fails the
signature, a changed spelling the canonical check).

>>> station = new_signing_key()
>>> text, code = seal(station, "usv", {"link.key": "00" * 16}, now_ns=0)
>>> opened = open_bundle(text, code, now_ns=1)
>>> opened.drone, opened.files["link.key"] == "00" * 16
('usv', True)
"""

from __future__ import annotations

import base64
import binascii
import hashlib
import json
import secrets
from dataclasses import dataclass
from typing import Any

from cryptography.exceptions import InvalidSignature, InvalidTag
from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey, Ed25519PublicKey
from cryptography.hazmat.primitives.ciphers.aead import AESGCM
from cryptography.hazmat.primitives.kdf.scrypt import Scrypt

FORMAT = "modd-pair"
VERSION = 1
SUFFIX = ".modd-pair"
DOMAIN = b"modd-pair-v1\n"
#: A bundle is valid this long after it is made (carried on a USB stick to the quay).
LIFETIME_S = 7 * 86_400
#: Bundles are small (configs and a model); anything bigger is a mistake or an attack.
MAX_BUNDLE_BYTES = 4 * 1024 * 1024
#: scrypt cost: ~32 MiB and ~0.1 s on a laptop, ~1 s on a Raspberry Pi 4.
SCRYPT_N, SCRYPT_R, SCRYPT_P = 2**15, 8, 1
#: The code: 20 symbols of Crockford's base32 (100 bits), shown in groups of 5.
CODE_ALPHABET = "0123456789ABCDEFGHJKMNPQRSTVWXYZ"
CODE_SYMBOLS = 20
_CODE_ALIASES = str.maketrans({"O": "0", "I": "1", "L": "1", "U": "V"})


class BundleError(ValueError):
    """A bundle that is refused; the message says why, in the operator's words."""


@dataclass(frozen=True)
class Opened:
    """A verified, decrypted bundle."""

    drone: str
    issued_ns: int
    fingerprint: str
    public_key: bytes
    files: dict[str, Any]


@dataclass(frozen=True)
class Verified:
    """A bundle whose signature holds, not yet decrypted."""

    doc: dict[str, Any]
    drone: str
    issued_ns: int
    expires_ns: int
    public_key: bytes

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.public_key)


def canonical(doc: dict[str, Any]) -> bytes:
    return (
        json.dumps(doc, sort_keys=True, separators=(",", ":"), ensure_ascii=True) + "\n"
    ).encode()


def _b64(data: bytes) -> str:
    return base64.b64encode(data).decode("ascii")


def _unb64(text: Any, what: str) -> bytes:
    try:
        return base64.b64decode(str(text), validate=True)
    except (binascii.Error, ValueError):
        raise BundleError(f"the bundle is damaged or was altered ({what} is not base64)") from None


def new_signing_key() -> Ed25519PrivateKey:
    return Ed25519PrivateKey.generate()


def public_bytes(key: Ed25519PublicKey) -> bytes:
    from cryptography.hazmat.primitives.serialization import Encoding, PublicFormat

    return key.public_bytes(Encoding.Raw, PublicFormat.Raw)


def fingerprint(public: bytes) -> str:
    """``SHA256:`` and the first 16 bytes of the key's SHA-256, in hex pairs.

    >>> fingerprint(bytes(32))[:20]
    'SHA256:66:68:7a:ad:f'
    """
    digest = hashlib.sha256(public).hexdigest()[:32]
    return "SHA256:" + ":".join(digest[i : i + 2] for i in range(0, 32, 2))


def new_code() -> str:
    """A one-time code, e.g. ``7KQ2M-0XH4D-RT9AB-C3PZW``."""
    raw = "".join(secrets.choice(CODE_ALPHABET) for _ in range(CODE_SYMBOLS))
    return "-".join(raw[i : i + 5] for i in range(0, CODE_SYMBOLS, 5))


def normalize_code(code: str) -> str:
    """The code as typed (any case, dashes or spaces, O for 0, I or L for 1), canonical."""
    text = "".join(code.split()).replace("-", "").upper().translate(_CODE_ALIASES)
    if len(text) != CODE_SYMBOLS or any(c not in CODE_ALPHABET for c in text):
        raise BundleError(
            f"the pairing code should be {CODE_SYMBOLS} letters and digits "
            "(groups of 5, e.g. 7KQ2M-0XH4D-RT9AB-C3PZW); check what you typed"
        )
    return text


def _derive(code: str, kdf: dict[str, Any]) -> bytes:
    n, r, p = int(kdf["n"]), int(kdf["r"]), int(kdf["p"])
    if (n, r, p) != (SCRYPT_N, SCRYPT_R, SCRYPT_P):  # signed, but never let a file set the cost
        raise BundleError(
            f"the bundle asks for scrypt n={n} r={r} p={p}; this drone reads only "
            f"n={SCRYPT_N} r={SCRYPT_R} p={SCRYPT_P} (a newer workbench? update modd-drone)"
        )
    salt = _unb64(kdf["salt"], "the salt")
    return Scrypt(salt=salt, length=32, n=n, r=r, p=p).derive(normalize_code(code).encode())


def _clear(doc: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in doc.items() if k not in ("ciphertext", "signature")}


def seal(
    station: Ed25519PrivateKey,
    drone: str,
    files: dict[str, Any],
    now_ns: int,
    code: str | None = None,
) -> tuple[bytes, str]:
    """The bundle's bytes and its one-time code (drawn here unless given)."""
    code = code or new_code()
    public = public_bytes(station.public_key())
    doc: dict[str, Any] = {
        "format": FORMAT,
        "version": VERSION,
        "drone": drone,
        "issued_ns": now_ns,
        "expires_ns": now_ns + LIFETIME_S * 1_000_000_000,
        "station": {"public_key": _b64(public), "fingerprint": fingerprint(public)},
        "kdf": {"name": "scrypt", "n": SCRYPT_N, "r": SCRYPT_R, "p": SCRYPT_P},
        "aead": {"name": "AES-256-GCM", "nonce": _b64(secrets.token_bytes(12))},
    }
    doc["kdf"]["salt"] = _b64(secrets.token_bytes(16))
    key = _derive(code, doc["kdf"])
    payload = canonical({"drone": drone, "files": files})
    nonce = base64.b64decode(doc["aead"]["nonce"])
    doc["ciphertext"] = _b64(AESGCM(key).encrypt(nonce, payload, DOMAIN + canonical(_clear(doc))))
    doc["signature"] = _b64(station.sign(DOMAIN + canonical({**doc, "signature": ""})))
    return canonical(doc), code


_FIELDS = {
    "format": str,
    "version": int,
    "drone": str,
    "issued_ns": int,
    "expires_ns": int,
    "station": dict,
    "kdf": dict,
    "aead": dict,
    "ciphertext": str,
    "signature": str,
}


def _parse(data: bytes) -> dict[str, Any]:
    if len(data) > MAX_BUNDLE_BYTES:
        raise BundleError(f"not a pairing bundle: {len(data)} bytes, more than {MAX_BUNDLE_BYTES}")
    try:
        doc = json.loads(data.decode("ascii"))
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise BundleError(f"the bundle is damaged or was altered (unreadable: {exc})") from None
    if not isinstance(doc, dict) or doc.get("format") != FORMAT:
        raise BundleError("not a pairing bundle (no format modd-pair); a .modd-pair file is needed")
    if isinstance(doc.get("version"), int) and doc["version"] != VERSION:
        raise BundleError(
            f"pairing bundle version {doc.get('version')!r}; this drone reads version {VERSION}"
        )
    for name, kind in _FIELDS.items():
        if not isinstance(doc.get(name), kind) or isinstance(doc.get(name), bool):
            raise BundleError(f"the bundle is damaged or was altered (field {name!r})")
    if canonical(doc) != data:
        raise BundleError(
            "the bundle is damaged or was altered (its bytes are not as the base station "
            "wrote them: copy the file as it is, not through an editor)"
        )
    return doc


def verify(data: bytes) -> Verified:
    """The bundle's clear part, once its Ed25519 signature holds (by the key it names:
    whether that key is the drone's base station is the caller's check)."""
    doc = _parse(data)
    public = _unb64(doc["station"].get("public_key"), "the station's key")
    try:
        Ed25519PublicKey.from_public_bytes(public).verify(
            _unb64(doc["signature"], "the signature"),
            DOMAIN + canonical({**doc, "signature": ""}),
        )
    except (InvalidSignature, ValueError):
        raise BundleError(
            "the bundle was altered or damaged: its signature does not hold; "
            "make a new one on the workbench"
        ) from None
    return Verified(doc, doc["drone"], doc["issued_ns"], doc["expires_ns"], public)


def decrypt(bundle: Verified, code: str) -> Opened:
    """The payload of a verified bundle; BundleError on a wrong code."""
    doc = bundle.doc
    key = _derive(code, doc["kdf"])
    nonce = _unb64(doc["aead"].get("nonce"), "the nonce")
    try:
        plain = AESGCM(key).decrypt(
            nonce, _unb64(doc["ciphertext"], "the ciphertext"), DOMAIN + canonical(_clear(doc))
        )
    except (InvalidTag, ValueError):
        raise BundleError(
            "wrong pairing code: it does not open this bundle (the code is shown once, "
            "with the bundle; a new bundle has a new code)"
        ) from None
    payload = json.loads(plain)
    if payload.get("drone") != bundle.drone or not isinstance(payload.get("files"), dict):
        raise BundleError("the bundle's sealed part is not for the drone its label names")
    return Opened(
        bundle.drone, bundle.issued_ns, bundle.fingerprint, bundle.public_key, payload["files"]
    )


def open_bundle(data: bytes, code: str, now_ns: int) -> Opened:
    """Verify, check the time window, decrypt (no pinning: :mod:`.install` does that)."""
    bundle = verify(data)
    check_time(bundle, now_ns)
    return decrypt(bundle, code)


def check_time(bundle: Verified, now_ns: int) -> None:
    if now_ns > bundle.expires_ns:
        raise BundleError(
            f"the bundle expired {utc_text(bundle.expires_ns)} (bundles are valid "
            f"{LIFETIME_S // 86_400} days); make a new one on the workbench"
        )
    if bundle.issued_ns > now_ns + 300 * 1_000_000_000:
        raise BundleError(
            f"the bundle was made {utc_text(bundle.issued_ns)}, in this drone's future: "
            "set the drone's clock (timedatectl) and try again"
        )


def utc_text(ns: int) -> str:
    from datetime import UTC, datetime

    return datetime.fromtimestamp(ns / 1e9, UTC).strftime("%Y-%m-%d %H:%M UTC")
