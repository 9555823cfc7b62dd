"""Generated artefacts per role as one zip (the generators' own output):
driver projects for the integrator, broker configs for the operator,
subscriber stubs for the scientist. Deterministic: same model, same bytes.

>>> data = role_zip(model, "operator")          # doctest: +SKIP
"""

from __future__ import annotations

import io
import zipfile
from pathlib import Path
from typing import Any

from modd_gen.context import Station
from modd_gen.generate import ROLES, generate

TARGETS: tuple[str, ...] = tuple(ROLES)
#: A fixed timestamp inside the zip, so that the bytes depend on the model only.
_EPOCH = (2024, 1, 1, 0, 0, 0)


def as_run(model: dict[str, Any], archive_dir: Path | None) -> dict[str, Any]:
    """The model with the ingress socket and archive directory of the run the
    backend watches, when it watches a ``modd up`` run (``make run``: the
    archive directory is ``<workdir>/archive`` and the PubBroker's ingress
    ``<workdir>/ingress.sock``), so generated drivers and their READMEs name
    the paths that run actually uses. Otherwise the model as it is.

    >>> as_run({"pubBroker": {"logPath": "/logs"}}, None)
    {'pubBroker': {'logPath': '/logs'}}
    """
    if archive_dir is None:
        return model
    socket = archive_dir.parent / "ingress.sock"
    if not socket.exists() or not isinstance(model.get("pubBroker"), dict):
        return model
    broker = {
        **model["pubBroker"],
        "logPath": str(archive_dir),
        "ingress": {**model["pubBroker"].get("ingress", {}), "unixSocket": str(socket)},
    }
    return {**model, "pubBroker": broker}


def station_of(connect: tuple[str, ...], credentials: Path | None) -> Station | None:
    """The base station this backend connects to, for the scientist's
    subscribers: the SubBroker's zenoh endpoint, and the viewer's credentials
    file beside the backend's own (``make run``'s ``data/credentials``), named
    by its path, never read.

    >>> station_of(("tcp/127.0.0.1:7447",), None)
    Station(zenoh_connect='tcp/127.0.0.1:7447', viewer_credentials=None)
    """
    if not connect:
        return None
    viewer = credentials.parent / "viewer.cred" if credentials is not None else None
    shown = str(viewer) if viewer is not None and viewer.exists() else None
    return Station(connect[0], shown)


def role_zip(
    model: dict[str, Any], role: str, folder: str, station: Station | None = None
) -> bytes:
    """The role's artefacts under ``folder/`` in a zip, with INDEX.txt listing
    each file and whether it is regenerated or the user's once written."""
    artifacts = generate(model, role, station)
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        index = [f"{a.ownership.value:<9} {a.path}" for a in artifacts]
        _add(z, f"{folder}/INDEX.txt", "\n".join(index) + "\n", False)
        for a in artifacts:
            _add(z, f"{folder}/{a.path}", a.content, a.executable)
    return buf.getvalue()


def _add(z: zipfile.ZipFile, name: str, content: str, executable: bool) -> None:
    info = zipfile.ZipInfo(name, date_time=_EPOCH)
    info.compress_type = zipfile.ZIP_DEFLATED
    info.external_attr = (0o755 if executable else 0o644) << 16
    z.writestr(info, content.encode("utf-8"))


def content_disposition(filename: str) -> str:
    """``attachment`` with the name per RFC 6266: an ASCII fallback (quotes,
    slashes, backslashes and controls replaced: a file name, not a path) and
    the exact name as ``filename*``.

    >>> content_disposition('a"b-températur.csv')
    'attachment; filename="a_b-temp_ratur.csv"; filename*=UTF-8\\'\\'a%22b-temp%C3%A9ratur.csv'
    """
    from urllib.parse import quote

    fallback = "".join(c if 0x20 <= ord(c) < 0x7F and c not in '"\\;/' else "_" for c in filename)
    return f"attachment; filename=\"{fallback}\"; filename*=UTF-8''{quote(filename, safe='')}"
