"""Writing an opened pairing bundle into the drone's configuration directory
(``/etc/modd``): every file atomically (a temporary file beside it, synced,
renamed), secrets 0600 and owned by the service user, the station's key
pinned so that a bundle from another base station or an older one is refused.

>>> try:
...     check_drone("usv", "asv", "/etc/modd/pubbroker.json")
... except BundleError as exc:
...     print(str(exc)[:62])
this bundle is for drone 'usv', but this drone is 'asv' (/etc/
"""

from __future__ import annotations

import base64
import json
import os
import pwd
import secrets
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .bundle import BundleError, Opened, Verified, fingerprint, utc_text

#: What a bundle may carry and the mode each is written with (0600: a secret).
FILES = {"pubbroker.json": 0o644, "model.json": 0o644, "link.key": 0o600}
SECRETS = frozenset(n for n, m in FILES.items() if m == 0o600)
#: The drone's record of its pairing: the station's key (pinned) and the last bundle's time.
PAIRED = "paired.json"
SERVICES = ("modd-pubbroker", "modd-sensors", "modd-mavlink")


@dataclass
class Written:
    """What an import wrote, for the operator."""

    config_dir: Path
    files: list[tuple[Path, int]] = field(default_factory=list)
    owner: str | None = None


def paired_record(config_dir: Path) -> dict[str, Any] | None:
    path = config_dir / PAIRED
    try:
        record = json.loads(path.read_text())
    except FileNotFoundError:
        return None
    except (OSError, ValueError) as exc:
        raise BundleError(f"{path}: unreadable ({exc}); remove it to pair anew") from None
    return record if isinstance(record, dict) else None


def current_drone(config_dir: Path) -> tuple[str, str] | None:
    """The drone this machine is configured as (its pubbroker.json's name), and where."""
    path = config_dir / "pubbroker.json"
    try:
        name = json.loads(path.read_text()).get("name")
    except (OSError, ValueError, AttributeError):
        return None
    return (str(name), str(path)) if name else None


def check_drone(bundle_drone: str, this_drone: str, where: str) -> None:
    if bundle_drone != this_drone:
        raise BundleError(
            f"this bundle is for drone {bundle_drone!r}, but this drone is {this_drone!r} "
            f"({where}): make the bundle for {this_drone!r} on the workbench"
        )


def check_pairing(bundle: Verified, config_dir: Path, new_station: bool) -> None:
    """Refuse a bundle of another base station (unless ``new_station``) or one not newer
    than the last imported (a replay of an older bundle)."""
    record = paired_record(config_dir)
    if record is None:
        return
    pinned = str(record.get("station_fingerprint", ""))
    if pinned != bundle.fingerprint and not new_station:
        raise BundleError(
            f"this bundle is signed by base station {bundle.fingerprint}, but this drone is "
            f"paired with {pinned}; if the drone moves to that station, run again with "
            "--new-station"
        )
    last = int(record.get("issued_ns", 0))
    if pinned == bundle.fingerprint and bundle.issued_ns <= last:
        raise BundleError(
            f"this bundle (made {utc_text(bundle.issued_ns)}) is not newer than the one imported "
            f"last (made {utc_text(last)}): an old copy? make a new one on the workbench"
        )


def _owner(name: str | None) -> tuple[int, int] | None:
    if name is None:
        return None
    try:
        entry = pwd.getpwnam(name)
    except KeyError:
        raise BundleError(f"no user {name!r} on this machine (is modd-drone installed?)") from None
    return entry.pw_uid, entry.pw_gid


def write_atomic(path: Path, data: bytes, mode: int, owner: tuple[int, int] | None) -> None:
    """``path`` replaced by ``data`` at once: a reader sees the old file or the new one."""
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, mode)
    try:
        os.fchmod(fd, mode)
        if owner is not None:
            os.fchown(fd, *owner)
        os.write(fd, data)
        os.fsync(fd)
    except BaseException:
        os.close(fd)
        tmp.unlink(missing_ok=True)
        raise
    os.close(fd)
    os.replace(tmp, path)


def _contents(opened: Opened, config_dir: Path) -> dict[str, bytes]:
    unknown = set(opened.files) - set(FILES)
    if unknown or "pubbroker.json" not in opened.files or "link.key" not in opened.files:
        raise BundleError(f"the bundle carries unexpected files: {sorted(opened.files)}")
    out: dict[str, bytes] = {}
    for name, value in opened.files.items():
        if name.endswith(".json"):
            if name == "pubbroker.json":  # the key is where this import puts it
                link = {**value["link"], "key": f"file:{config_dir.absolute() / 'link.key'}"}
                value = {**value, "link": link}
            out[name] = (json.dumps(value, indent=2) + "\n").encode()
        else:
            out[name] = str(value).encode() + b"\n"
    return out


def install(opened: Opened, config_dir: Path, owner: str | None) -> Written:
    """Write the bundle's files into ``config_dir`` (made 0755 if missing), then the
    pairing record; secrets owned by ``owner`` when given (root only)."""
    ids = _owner(owner)
    contents = _contents(opened, config_dir)
    config_dir.mkdir(mode=0o755, parents=True, exist_ok=True)
    written = Written(config_dir, owner=owner)
    for name, data in contents.items():
        mode = FILES[name]
        path = config_dir / name
        write_atomic(path, data, mode, ids if name in SECRETS else None)
        written.files.append((path, mode))
    record = {
        "drone": opened.drone,
        "issued_ns": opened.issued_ns,
        "station_fingerprint": fingerprint(opened.public_key),
        "station_public_key": base64.b64encode(opened.public_key).decode(),
    }
    path = config_dir / PAIRED
    write_atomic(path, (json.dumps(record, indent=2) + "\n").encode(), 0o644, None)
    written.files.append((path, 0o644))
    return written
