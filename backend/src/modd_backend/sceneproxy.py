"""The 3D scene through the backend's own origin: a reverse proxy (HTTP and
WebSocket) at ``/scene/`` to the viser server, which listens on loopback only.

Contract (docs/security.md, "3D scene"):

- every request needs a session (cookie or bearer header) of a user holding
  a role (401 / 403 otherwise), like live values on the stream WebSocket;
- the WebSocket upgrade follows the rules of wsrelay.py (Origin, session,
  role, closed when the session ends or the roles change);
- viser's own port answers only the proxy (a per-server secret: scenegate.py);
- viser's page is one HTML file whose inline bootstrap unpacks and inserts an
  inline module script. The page gets its own Content-Security-Policy that
  allows exactly those two scripts by their SHA-256 (computed here from the
  page the upstream serves), never ``'unsafe-inline'``; the workbench's own
  CSP is not widened.

>>> csp_hash("alert(1)")
"'sha256-bhHHL3z2vDgxUt0W3dWQOrprscmda2Y5pLsLg4GF+pI='"
"""

from __future__ import annotations

import asyncio
import base64
import contextlib
import hashlib
import html
import re
from collections.abc import Awaitable
from dataclasses import dataclass

import zstandard
from starlette.websockets import WebSocket
from websockets.asyncio.client import ClientConnection
from websockets.asyncio.client import connect as ws_connect
from websockets.typing import Subprotocol

from .deps import AppState
from .scenegate import SECRET_HEADER
from .wsrelay import admit, relay

#: Largest upstream answer relayed (viser's page is ~0.8 MB).
MAX_UPSTREAM_BYTES = 32 * 1024 * 1024
_SCRIPT = re.compile(r"<script([^>]*)>(.*?)</script>", re.DOTALL | re.IGNORECASE)
_ATTR = re.compile(r'data-(p|ss|cs)="([^"]*)"')
_ALPHABET = (
    "!#$%()*+,-./0123456789:;=?@ABCDEFGHIJKLMNOPQRSTUVWXYZ[\\]^_abcdefghijklmnopqrstuvwxyz{|}~"
)
_DIGIT = {c: i for i, c in enumerate(_ALPHABET)}


def csp_hash(text: str) -> str:
    """The CSP source expression allowing an inline script of this text."""
    digest = hashlib.sha256(text.encode("utf-8")).digest()
    return f"'sha256-{base64.b64encode(digest).decode()}'"


def base88_decode(text: str) -> bytes:
    """viser's packing of binary data into an HTML attribute (its ``de``):
    5 characters per 4 bytes, big-endian; a tail of r characters is r-1 bytes.

    >>> base88_decode(base88_encode(b"viser!"))
    b'viser!'
    """
    out = bytearray()
    whole = len(text) - len(text) % 5
    for i in range(0, whole, 5):
        v = 0
        for ch in text[i : i + 5]:
            v = v * 88 + _DIGIT[ch]
        out += (v & 0xFFFFFFFF).to_bytes(4, "big")
    tail = text[whole:]
    if tail:
        v = 0
        for ch in tail:
            v = v * 88 + _DIGIT[ch]
        out += (v % (1 << (8 * (len(tail) - 1)))).to_bytes(len(tail) - 1, "big")
    return bytes(out)


def base88_encode(data: bytes) -> str:
    """The inverse of :func:`base88_decode` (for tests)."""
    out = []
    whole = len(data) - len(data) % 4
    for i in range(0, whole, 4):
        v = int.from_bytes(data[i : i + 4], "big")
        out.append("".join(_ALPHABET[v // 88**k % 88] for k in range(4, -1, -1)))
    tail = data[whole:]
    if tail:
        v = int.from_bytes(tail, "big")
        out.append("".join(_ALPHABET[v // 88**k % 88] for k in range(len(tail), -1, -1)))
    return "".join(out)


def _unpacked_module(attrs: str) -> str | None:
    """The module script viser's bootstrap inserts: ``data-p`` is zstd of the
    page's CSS (``data-ss`` bytes) followed by its JavaScript (``data-cs``)."""
    found = dict(_ATTR.findall(attrs))
    if not {"p", "ss", "cs"} <= found.keys():
        return None
    ss, cs = int(found["ss"]), int(found["cs"])
    if ss + cs > MAX_UPSTREAM_BYTES * 8:
        return None
    packed = base88_decode(html.unescape(found["p"]))
    raw = zstandard.ZstdDecompressor().decompress(packed, max_output_size=ss + cs)
    return raw[ss : ss + cs].decode("utf-8", errors="replace")


def script_hashes(page: str) -> list[str]:
    """CSP hashes of every inline script of the page, and of the module
    script its bootstrap unpacks (what the page runs, nothing else)."""
    hashes: list[str] = []
    for attrs, body in _SCRIPT.findall(page):
        if "src=" in attrs.lower():
            continue
        hashes.append(csp_hash(body))
        module = _unpacked_module(attrs)
        if module is not None:
            hashes.append(csp_hash(module))
    return hashes


def scene_csp(hashes: list[str], host: str) -> str:
    """The policy of the proxied page: its own scripts by hash, WebAssembly
    (viser's zstd decoder), its WebSocket at ``/scene`` and framing by the
    workbench only."""
    scripts = " ".join(hashes) or "'none'"
    return (
        "default-src 'none'; "
        f"script-src {scripts} 'wasm-unsafe-eval'; "
        "style-src 'unsafe-inline'; img-src data: blob:; font-src data:; "
        f"connect-src ws://{host}/scene wss://{host}/scene data: blob:; "
        "worker-src blob:; base-uri 'none'; form-action 'none'; object-src 'none'; "
        "frame-ancestors 'self'"
    )


@dataclass(frozen=True)
class Upstream:
    status: int
    headers: dict[str, str]
    body: bytes


async def fetch(port: int, path: str, secret: str, timeout_s: float = 10.0) -> Upstream:
    """GET ``path`` from the viser server on 127.0.0.1:``port`` (HTTP/1.1,
    identity encoding, bounded size), with the secret it asks for (scenegate.py)."""

    async def run() -> Upstream:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        try:
            writer.write(
                f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
                f"{SECRET_HEADER}: {secret}\r\n"
                "Accept-Encoding: identity\r\nConnection: close\r\n\r\n".encode()
            )
            await writer.drain()
            head = await reader.readuntil(b"\r\n\r\n")
            lines = head.decode("latin-1").split("\r\n")
            status = int(lines[0].split(" ", 2)[1])
            headers = {
                k.strip().lower(): v.strip()
                for k, _, v in (line.partition(":") for line in lines[1:] if line)
            }
            length = int(headers.get("content-length", "-1"))
            if length > MAX_UPSTREAM_BYTES:
                raise ValueError("the scene's answer is too large")
            if length >= 0:
                body = await reader.readexactly(length)
            else:
                body = await reader.read(MAX_UPSTREAM_BYTES + 1)
                if len(body) > MAX_UPSTREAM_BYTES:
                    raise ValueError("the scene's answer is too large")
            return Upstream(status, headers, body)
        finally:
            writer.close()
            with contextlib.suppress(Exception):
                await writer.wait_closed()

    return await asyncio.wait_for(run(), timeout_s)


class PagePolicies:
    """CSP per page body (viser's page is static: computed once)."""

    def __init__(self) -> None:
        self._hashes: dict[bytes, list[str]] = {}

    def hashes(self, body: bytes) -> list[str]:
        key = hashlib.sha256(body).digest()
        found = self._hashes.get(key)
        if found is None:
            found = script_hashes(body.decode("utf-8", errors="replace"))
            if len(self._hashes) > 8:
                self._hashes.clear()
            self._hashes[key] = found
        return found


# --- the WebSocket ---------------------------------------------------------


async def relay_socket(websocket: WebSocket, state: AppState, port: int, secret: str) -> None:
    """Authenticate the upgrade (wsrelay.admit), then relay frames both ways
    with the viser server until either side closes or the session ends."""
    admitted = await admit(websocket, state, "the 3D scene")
    if admitted is None:
        return
    offered = [Subprotocol(p) for p in websocket.scope.get("subprotocols", [])][:4]

    def connect() -> Awaitable[ClientConnection]:
        return ws_connect(
            f"ws://127.0.0.1:{port}",
            subprotocols=offered or None,
            compression=None,
            max_size=64 * 1024 * 1024,
            open_timeout=5,
            additional_headers={SECRET_HEADER: secret},
        )

    await relay(websocket, state, admitted, connect, "the 3D scene")
