"""Guards every request passes before any route (one ASGI middleware), and
the bound on heavy routes.

- ``Host`` must name this service (loopback names, the bound host, and
  ``Settings.allowed_hosts``): 400 otherwise (DNS rebinding).
- A request body is read here, at most ``max_body_bytes`` (413 beyond, with
  or without a Content-Length), and a JSON body nested deeper than
  ``max_json_depth`` is refused with 422 before any route sees it: a request
  answered with an error stores nothing.
- Every answer carries the security headers (a CSP without inline scripts,
  ``frame-ancestors 'none'`` except for the same-origin 3D scene, nosniff,
  Referrer-Policy).

Heavy routes (CSV export, series, deploy) take a slot of :class:`HeavyLimiter`
or wait their turn in a bounded queue (a few per user, a bound in all, at most
``wait_s``); beyond it they are refused with 429 (this user's share is taken)
or 503 (all are), both with ``Retry-After``; ``/api/health`` never waits.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections import deque
from collections.abc import AsyncIterator, Iterator
from contextlib import asynccontextmanager, contextmanager
from typing import Any

from modd_model.jsondepth import json_depth
from starlette.concurrency import run_in_threadpool
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from .errors import ApiError, retry_later
from .settings import Settings

#: Mount point of the reverse-proxied 3D scene (routers/scene.py).
SCENE_PREFIX = "/scene/"
_BODY_METHODS = frozenset({"POST", "PUT", "PATCH", "DELETE"})
#: Bodies from this size on are depth-checked off the event loop.
_THREAD_BODY_BYTES = 64 * 1024


def csp(path: str, host: str, tile_origins: tuple[str, ...] = ()) -> str:
    """The Content-Security-Policy of an answer: no inline or foreign
    scripts; only the 3D scene (same origin) may be framed, by the workbench.
    (The scene's page sets its own, stricter policy: sceneproxy.py.)
    Images come from this origin only, and from the map tile servers the
    service was configured with (``Settings.tile_origins``)."""
    scene = path.startswith(SCENE_PREFIX)
    if path == "/docs":  # Swagger UI: an inline bootstrap, its files served here (apidocs.py)
        return (
            "default-src 'self'; script-src 'self' 'unsafe-inline'; "
            "style-src 'self' 'unsafe-inline'; img-src 'self' data:; "
            "frame-ancestors 'none'; object-src 'none'"
        )
    if path == "/redoc":  # FastAPI's ReDoc page: inline bootstrap, CDN assets
        cdn = "https://cdn.jsdelivr.net"
        return (
            f"default-src 'self'; script-src 'self' 'unsafe-inline' {cdn}; "
            f"style-src 'self' 'unsafe-inline' {cdn}; img-src 'self' data: "
            "https://fastapi.tiangolo.com; frame-ancestors 'none'; object-src 'none'"
        )
    ancestors = "'self'" if scene else "'none'"
    images = " ".join(("'self' data: blob:", *tile_origins))
    return (
        "default-src 'self'; "
        "script-src 'self'; "
        "style-src 'self' 'unsafe-inline'; "
        f"img-src {images}; font-src 'self' data:; "
        f"connect-src 'self' ws://{host} wss://{host}; "
        "worker-src 'self' blob:; frame-src 'self'; object-src 'none'; base-uri 'none'; "
        f"form-action 'self'; frame-ancestors {ancestors}"
    )


def security_headers(
    path: str, host: str, tile_origins: tuple[str, ...] = ()
) -> list[tuple[bytes, bytes]]:
    framing = b"SAMEORIGIN" if path.startswith(SCENE_PREFIX) else b"DENY"
    return [
        (b"content-security-policy", csp(path, host, tile_origins).encode()),
        (b"x-content-type-options", b"nosniff"),
        (b"referrer-policy", b"no-referrer"),
        (b"x-frame-options", framing),
        (b"cross-origin-opener-policy", b"same-origin"),
    ]


class _TooLarge(Exception):
    pass


class Guard:
    """The ASGI middleware described in the module docstring."""

    def __init__(self, app: ASGIApp, settings: Settings) -> None:
        self.app = app
        self.settings = settings

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {
            k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])
        }
        host = headers.get("host", "")
        if not self.settings.host_allowed(host):
            if scope["type"] == "websocket":
                await send({"type": "websocket.close", "code": 4400, "reason": "Host not allowed"})
                return
            await _plain(
                send,
                400,
                f"Host {host!r} is not allowed here (settings: allowed_hosts)",
                scope["path"],
                "localhost",
            )
            return
        if scope["type"] == "websocket":
            await self.app(scope, receive, send)
            return
        path: str = scope["path"]
        extra = security_headers(path, host, self.settings.tile_origins)

        async def send_with_headers(message: Message) -> None:
            if message["type"] == "http.response.start":
                names = {k.lower() for k, _ in message.get("headers", [])}
                message["headers"] = list(message.get("headers", [])) + [
                    h for h in extra if h[0] not in names
                ]
            await send(message)

        if scope["method"] not in _BODY_METHODS:
            await self.app(scope, receive, send_with_headers)
            return
        limit = self.settings.max_body_bytes
        declared = headers.get("content-length")
        if declared is not None and declared.isdigit() and int(declared) > limit:
            await _too_large(send, limit, path, host)
            return
        try:
            body = await _read_body(receive, limit)
        except _TooLarge:
            await _too_large(send, limit, path, host)
            return
        ctype = headers.get("content-type", "")
        if body[:1] in (b"{", b"[") or "json" in ctype:
            # a model of megabytes is checked in a thread: the loop keeps serving
            depth = (
                json_depth(body)
                if len(body) < _THREAD_BODY_BYTES
                else await run_in_threadpool(json_depth, body)
            )
            if depth > self.settings.max_json_depth:
                await _json_error(
                    send,
                    422,
                    {
                        "detail": f"the JSON body is nested {depth} levels deep; at most "
                        f"{self.settings.max_json_depth} are accepted"
                    },
                    path,
                    host,
                )
                return
        replayed = False

        async def replay() -> Message:
            nonlocal replayed
            if not replayed:
                replayed = True
                return {"type": "http.request", "body": body, "more_body": False}
            return await receive()

        await self.app(scope, replay, send_with_headers)


async def _read_body(receive: Receive, limit: int) -> bytes:
    chunks: list[bytes] = []
    size = 0
    while True:
        message = await receive()
        if message["type"] == "http.disconnect":
            break
        chunk = message.get("body", b"")
        size += len(chunk)
        if size > limit:
            raise _TooLarge
        chunks.append(chunk)
        if not message.get("more_body", False):
            break
    return b"".join(chunks)


async def _json_error(send: Send, status: int, body: dict[str, Any], path: str, host: str) -> None:
    data = json.dumps(body).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(data)).encode()),
                (b"connection", b"close"),
                *security_headers(path, host),
            ],
        }
    )
    await send({"type": "http.response.body", "body": data})


async def _too_large(send: Send, limit: int, path: str, host: str) -> None:
    await _json_error(
        send,
        413,
        {"detail": f"the request body exceeds {limit} bytes", "limit_bytes": limit},
        path,
        host,
    )


async def _plain(send: Send, status: int, text: str, path: str, host: str) -> None:
    await _json_error(send, status, {"detail": text}, path, host)


def _behind_earlier() -> ApiError:
    """A user's heavy request behind that user's earlier ones (the queue full, or not yet first)."""
    return retry_later(
        429, "this user's earlier heavy requests are waiting their turn; retry shortly", 1
    )


class HeavyLimiter:
    """Slots for heavy requests: ``per_user`` each and ``total`` in all.

    :meth:`turn` (the routes' way in) waits for a slot: a user's requests in
    the order they came, polled every ``poll_s`` on the event loop (a waiting
    request holds no thread), at most ``wait_s``; at most ``queue_per_user``
    of a user's requests and ``queue_total`` in all wait, and one beyond is
    refused at once, as is one that waited ``wait_s``: 429 (this user's share
    is taken) or 503 (all are), with ``Retry-After``. :meth:`slot` never
    waits."""

    def __init__(
        self,
        per_user: int,
        total: int,
        *,
        queue_per_user: int = 4,
        queue_total: int = 32,
        wait_s: float = 30.0,
        poll_s: float = 0.05,
    ) -> None:
        self.per_user = per_user
        self.total = total
        self.queue_per_user = queue_per_user
        self.queue_total = queue_total
        self.wait_s = wait_s
        self.poll_s = poll_s
        self.in_flight = 0
        self._by_user: dict[int, int] = {}
        self._waiting: dict[int, deque[object]] = {}
        self._lock = threading.Lock()

    @property
    def saturated(self) -> bool:
        return self.in_flight >= self.total

    @property
    def waiting(self) -> int:
        return sum(len(q) for q in self._waiting.values())

    def _refusal(self, user_id: int) -> ApiError | None:
        """Why no slot is free for this user now (under the lock), or None."""
        if self._by_user.get(user_id, 0) >= self.per_user:
            return retry_later(
                429,
                f"at most {self.per_user} heavy requests at once per user "
                f"(CSV, series, deploy), {self.queue_per_user} more waiting their "
                "turn; retry shortly",
                1,
            )
        if self.in_flight >= self.total:
            return retry_later(503, "the service is busy with heavy requests; retry shortly", 1)
        return None

    def _take(self, user_id: int) -> None:
        self.in_flight += 1
        self._by_user[user_id] = self._by_user.get(user_id, 0) + 1

    def _release(self, user_id: int) -> None:
        with self._lock:
            self.in_flight -= 1
            left = self._by_user[user_id] - 1
            if left:
                self._by_user[user_id] = left
            else:
                del self._by_user[user_id]

    @contextmanager
    def slot(self, user_id: int) -> Iterator[None]:
        with self._lock:
            refused = self._refusal(user_id)
            if refused is not None:
                raise refused
            self._take(user_id)
        try:
            yield
        finally:
            self._release(user_id)

    def _enqueue(self, user_id: int) -> object | None:
        """A slot at once (None), or a place in the user's queue; refused when that is full."""
        with self._lock:
            queue = self._waiting.get(user_id)
            refused = self._refusal(user_id)
            if refused is None and not queue:
                self._take(user_id)
                return None
            if refused is None:
                refused = _behind_earlier()
            full = queue is not None and len(queue) >= self.queue_per_user
            if full or self.waiting >= self.queue_total:
                raise refused
            ticket = object()
            self._waiting.setdefault(user_id, deque()).append(ticket)
            return ticket

    def _try_take(self, user_id: int, ticket: object) -> ApiError | None:
        """Take a slot if one is free and this ticket is the user's first; else why not."""
        with self._lock:
            refused = self._refusal(user_id) or (
                None if self._waiting[user_id][0] is ticket else _behind_earlier()
            )
            if refused is None:
                self._take(user_id)
                self._leave(user_id, ticket)
            return refused

    def _leave(self, user_id: int, ticket: object) -> None:
        queue = self._waiting.get(user_id)
        if queue is not None and ticket in queue:
            queue.remove(ticket)
            if not queue:
                del self._waiting[user_id]

    @asynccontextmanager
    async def turn(self, user_id: int) -> AsyncIterator[None]:
        ticket = self._enqueue(user_id)
        if ticket is not None:
            deadline = time.monotonic() + self.wait_s
            try:
                while (why := self._try_take(user_id, ticket)) is not None:
                    if time.monotonic() >= deadline:
                        raise why
                    await asyncio.sleep(self.poll_s)
            finally:
                with self._lock:
                    self._leave(user_id, ticket)
        try:
            yield
        finally:
            self._release(user_id)
