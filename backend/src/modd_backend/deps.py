"""What every route depends on: the app state, a database session, the
authenticated user and role checks.

>>> @router.post("/x", dependencies=[Depends(require(Role.operator))])   # doctest: +SKIP
"""

from __future__ import annotations

import asyncio
import functools
import hmac
import time
from collections import Counter
from collections.abc import AsyncIterator, Awaitable, Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Annotated, Any, Literal, TypeVar

from anyio import CapacityLimiter, to_thread
from fastapi import Depends, HTTPException, Request, WebSocket
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.orm import Session as Db

from .accounts import user_for_token
from .db import Store
from .foxglove import FoxgloveLive
from .loopback_tls import LoopbackTls
from .project_events import ProjectEvents
from .roles import Role
from .scene import SceneService
from .security import csrf_for
from .sessionwatches import SessionWatches
from .settings import Settings
from .socketcaps import SocketCaps
from .storework import has_role as has_role  # re-exported: the routes import it from here
from .storework import holding, known, store_work
from .storework import roles_of as roles_of
from .tables import User
from .throttle import KnownPairs, Throttle
from .tickets import ViewerTickets
from .zenoh_session import ZenohSession

if TYPE_CHECKING:
    from .archive_pool import ArchivePool
    from .guards import HeavyLimiter
    from .hub import SubscriptionHub
    from .reconcile import DroneStatuses
    from .replay import ReplaySlot
    from .storeproc import StoreProcesses

#: The workbench's session cookie (HttpOnly, SameSite=Strict) and the header
#: a cookie session must add to every unsafe request (CSRF).
SESSION_COOKIE = "modd_session"
CSRF_HEADER = "X-CSRF-Token"
SAFE_METHODS = frozenset({"GET", "HEAD", "OPTIONS"})
#: Threads running the hot routes' whole store work (:func:`in_store`): fewer
#: than the store's connection pool (5 + 10 overflow), so none waits for a
#: connection, and few enough that the event loop seldom waits for the GIL.
STORE_THREADS = 6
T = TypeVar("T")


@dataclass
class AppState:
    settings: Settings
    store: Store
    zenoh_session: ZenohSession | None
    scene: SceneService | None = None
    foxglove: FoxgloveLive | None = None
    replay: ReplaySlot | None = None
    hub: SubscriptionHub | None = None
    #: The last status of each drone (what it runs), fed by the hub.
    statuses: DroneStatuses | None = None
    #: Saves announced to the stream WebSockets watching a project.
    project_events: ProjectEvents = field(default_factory=ProjectEvents)
    heavy: HeavyLimiter | None = None
    #: The archive worker processes behind their per-user fair queue.
    archive_pool: ArchivePool | None = None
    login_accounts: Throttle = field(default_factory=lambda: Throttle(10, 300))
    login_addresses: Throttle = field(default_factory=lambda: Throttle(50, 300))
    #: Accounts that logged in from an address: past that address's lock (throttle.py).
    login_known: KnownPairs = field(default_factory=lambda: KnownPairs(30 * 86_400))
    #: Live WebSocket subscriptions per user id (event loop only).
    ws_counts: Counter[int] = field(default_factory=Counter)
    #: Stream sockets waiting for their first-message auth, per client address.
    ws_unauthenticated: Counter[str] = field(default_factory=Counter)
    #: Single-use tickets standing for a session in a viewer's URL (Foxglove).
    tickets: ViewerTickets = field(default_factory=ViewerTickets)
    #: The certificate the loopback Foxglove servers present (only the proxy trusts it).
    loopback_tls: LoopbackTls | None = None
    #: The login's own threads (routers/auth.py), set at start-up.
    login_threads: CapacityLimiter | None = None
    #: Threads closing store sessions (get_db), apart from the routes' pool.
    closing_threads: CapacityLimiter | None = None
    #: The hot routes' threads (in_store), apart from the routes' pool.
    store_threads: ThreadPoolExecutor | None = None
    #: The hot routes' store processes (storeproc.py); None: store_threads.
    store_procs: StoreProcesses | None = None
    #: Open WebSockets per user and per client address (socketcaps.py).
    socket_caps: SocketCaps = field(default_factory=lambda: SocketCaps(64, 512))
    #: One shared session re-check per session of open sockets (sessionwatch.py).
    session_watches: SessionWatches | None = None
    #: Result of the last background database ping (health).
    database: Literal["ok", "error", "unknown"] = "unknown"


async def get_state(request: Request) -> AppState:
    """(async: read on the event loop, never waiting for a worker thread)"""
    state: AppState = request.app.state.modd
    return state


def ws_state(websocket: WebSocket) -> AppState:
    state: AppState = websocket.app.state.modd
    return state


StateDep = Annotated[AppState, Depends(get_state)]


async def get_db(state: StateDep) -> AsyncIterator[Db]:
    """A store session for the request. Opened on the event loop (no I/O until
    its first query, made in the route's thread) and closed there when it
    never began a transaction; otherwise closed in a worker thread. Each
    worker-thread hop costs the event loop as much as a short request (issue
    41's profile), so the route's dependencies take as few as they can."""
    db = state.store.factory()
    try:
        yield db
    finally:
        if db.in_transaction():
            # threads of its own (as FastAPI's exits of sync dependencies): a
            # close waiting behind routes that wait for its connection would
            # hold them all until the pool's timeout
            await to_thread.run_sync(db.close, limiter=state.closing_threads)
        else:
            db.close()


DbDep = Annotated[Db, Depends(get_db)]
_bearer = HTTPBearer(auto_error=False, description="Token from POST /api/auth/login")


@dataclass(frozen=True)
class Credentials:
    """The session token of a request, and whether it came as the cookie."""

    token: str
    via_cookie: bool


async def credentials(
    request: Request,
    creds: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> Credentials:
    """A bearer token (API clients) or the session cookie (the workbench).
    With the cookie, unsafe methods need ``X-CSRF-Token`` (403 without)."""
    if creds is not None and creds.scheme.lower() == "bearer":
        return Credentials(creds.credentials, False)
    cookie = request.cookies.get(SESSION_COOKIE)
    if cookie:
        if request.method not in SAFE_METHODS:
            sent = request.headers.get(CSRF_HEADER, "")
            if not hmac.compare_digest(sent.encode(), csrf_for(cookie).encode()):
                raise HTTPException(
                    403,
                    f"a cookie session needs the {CSRF_HEADER} header on "
                    f"{request.method} (given by login and /api/auth/me)",
                )
        return Credentials(cookie, True)
    raise HTTPException(
        401, "missing bearer token or session cookie", headers={"WWW-Authenticate": "Bearer"}
    )


CredsDep = Annotated[Credentials, Depends(credentials)]


async def bearer_token(creds: CredsDep) -> str:
    return creds.token


TokenDep = Annotated[str, Depends(bearer_token)]


def current_user(db: DbDep, token: TokenDep) -> User:
    """The session's user. Its read ends here (the user's fields stay
    loaded): the connection goes back to the pool while the route waits for
    its worker thread, so requests waiting for threads never hold every
    connection that the running ones wait for."""
    user = user_for_token(db, token)
    db.commit()
    return known(user)


UserDep = Annotated[User, Depends(current_user)]


def require(*roles: Role) -> Callable[[User], Awaitable[User]]:
    """A dependency letting through users holding any of ``roles`` (or admin)."""

    async def check(user: UserDep) -> User:  # (async: no worker thread for a set test)
        return holding(user, roles)

    return check


async def in_store(
    state: AppState,
    creds: Credentials,
    roles: tuple[Role, ...],
    work: Callable[..., T],
    *args: Any,
) -> T:
    """``work(db, user, *args)`` for the request's user, in ONE hop (issue
    41: each hop costs the event loop as much as a short request): a store
    session is opened, the session token read (401) and ``roles`` checked
    (403; none: any user), ``work`` run and committed, and the session
    closed (:func:`store_work`). ``work`` also builds its answer there (e.g.
    the JSON bytes), so the event loop only sends it.

    The hop goes to a store process (storeproc.py, ``Settings.store_processes``):
    the work's Python then never holds this process's interpreter lock away
    from the event loop. ``work`` must be a module-level function and its
    arguments and result picklable. With no store processes it goes to
    ``state.store_threads`` (an executor's hop costs the loop about half of
    anyio's). Either way a request given up while its work runs lets it
    finish, and one not begun is never run."""
    if state.store_procs is not None:
        return await state.store_procs.run(creds.token, roles, work, args)
    call = functools.partial(store_work, state.store, creds.token, roles, work, args)
    return await asyncio.get_running_loop().run_in_executor(state.store_threads, call)


async def _heavy(request: Request, state: StateDep, user: UserDep) -> AsyncIterator[None]:
    # the archive workers' start bound (30 s) counts from here (archive_pool.py)
    request.state.heavy_since = time.monotonic()
    if state.heavy is None:
        yield
        return
    async with state.heavy.turn(user.id):
        yield


#: Route dependency of heavy routes (CSV, series, deploy): a slot of the
#: HeavyLimiter, waited for in its bounded queue, or 429/503 with Retry-After.
Heavy = Depends(_heavy)


def zenoh_session_of(state: AppState) -> ZenohSession:
    if state.zenoh_session is None:
        raise HTTPException(503, "zenoh is disabled in this backend's settings")
    return state.zenoh_session


async def raw_body(request: Request) -> bytes:
    """The request body as bytes (for routes taking a raw file)."""
    return await request.body()


RawBody = Annotated[bytes, Depends(raw_body)]
