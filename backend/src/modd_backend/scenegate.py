"""viser's port answers the backend's proxy alone.

viser listens on loopback, but a web page may open a WebSocket to any port
of 127.0.0.1, and viser checks no login. So every request to viser's port
(page files and the WebSocket upgrade) must carry a secret drawn per server
in this process (header :data:`SECRET_HEADER`, which only the proxy sends:
sceneproxy.py) and no ``Origin`` (a browser always sends one on a
WebSocket); anything else gets 403 before viser sees it.

viser has no hook for this: while its server starts, its module's
``websockets`` name is swapped for a view whose ``serve`` puts the check
in front of viser's own ``process_request`` (tested against the installed
viser: backend/tests/test_scene_proxy.py).
"""

from __future__ import annotations

import hmac
import http
import secrets
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

#: The header carrying the per-server secret (the proxy's requests only).
SECRET_HEADER = "X-Modd-Scene-Key"
_swap = threading.Lock()


def new_secret() -> str:
    return secrets.token_urlsafe(32)


def admitted(headers: Any, secret: str) -> bool:
    """Whether a request to viser's port comes from the backend's proxy.

    >>> admitted({SECRET_HEADER: "k"}, "k"), admitted({SECRET_HEADER: "k", "Origin": "x"}, "k")
    (True, False)
    """
    sent = str(headers.get(SECRET_HEADER) or "")
    return headers.get("Origin") is None and hmac.compare_digest(sent.encode(), secret.encode())


class _View:
    """A module seen through: ``overrides`` first, then the module itself."""

    def __init__(self, real: Any, **overrides: Any) -> None:
        self._real = real
        self.__dict__.update(overrides)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._real, name)


def _gated_serve(real_serve: Callable[..., Any], secret: str) -> Callable[..., Any]:
    def serve(*args: Any, process_request: Any = None, **kwargs: Any) -> Any:
        def check(connection: Any, request: Any) -> Any:
            if not admitted(request.headers, secret):
                return connection.respond(
                    http.HTTPStatus.FORBIDDEN, "the 3D scene is served through the workbench\n"
                )
            return None if process_request is None else process_request(connection, request)

        return real_serve(*args, process_request=check, **kwargs)

    return serve


@contextmanager
def gated_viser(secret: str) -> Iterator[None]:
    """While in it, a viser server that starts admits only ``secret``."""
    import websockets
    import websockets.asyncio.server as server
    from viser.infra import _infra

    view = _View(
        websockets,
        asyncio=_View(
            websockets.asyncio, server=_View(server, serve=_gated_serve(server.serve, secret))
        ),
    )
    with _swap:
        real = vars(_infra)["websockets"]
        setattr(_infra, "websockets", view)  # noqa: B010 (a name mypy cannot see)
        try:
            yield
        finally:
            setattr(_infra, "websockets", real)  # noqa: B010
