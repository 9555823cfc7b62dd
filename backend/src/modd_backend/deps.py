"""What every route depends on: the app state, a database session, the
authenticated user and role checks.

>>> @router.post("/x", dependencies=[Depends(require(Role.operator))])   # doctest: +SKIP
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Annotated

from fastapi import Depends, HTTPException, Request, WebSocket
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from sqlalchemy.orm import Session as Db

from .accounts import user_for_token
from .db import Store
from .foxglove import FoxgloveLive
from .roles import Role, parse_roles
from .scene import SceneService
from .settings import Settings
from .tables import User
from .zbridge import ZenohBridge


@dataclass
class AppState:
    settings: Settings
    store: Store
    bridge: ZenohBridge | None
    scene: SceneService | None = None
    foxglove: FoxgloveLive | None = None


def get_state(request: Request) -> AppState:
    state: AppState = request.app.state.modd
    return state


def ws_state(websocket: WebSocket) -> AppState:
    state: AppState = websocket.app.state.modd
    return state


StateDep = Annotated[AppState, Depends(get_state)]


def get_db(state: StateDep) -> Iterator[Db]:
    with state.store.session() as db:
        yield db


DbDep = Annotated[Db, Depends(get_db)]
_bearer = HTTPBearer(auto_error=False, description="Token from POST /api/auth/login")


def bearer_token(
    creds: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)],
) -> str:
    if creds is None or creds.scheme.lower() != "bearer":
        raise HTTPException(401, "missing bearer token", headers={"WWW-Authenticate": "Bearer"})
    return creds.credentials


TokenDep = Annotated[str, Depends(bearer_token)]


def current_user(db: DbDep, token: TokenDep) -> User:
    user = user_for_token(db, token)
    if user is None:
        raise HTTPException(
            401, "invalid or expired token", headers={"WWW-Authenticate": "Bearer"}
        )
    return user


UserDep = Annotated[User, Depends(current_user)]


def roles_of(user: User) -> set[str]:
    return parse_roles(user.roles)


def has_role(user: User, *roles: Role) -> bool:
    held = roles_of(user)
    return Role.admin in held or any(r in held for r in roles)


def require(*roles: Role) -> Callable[[User], User]:
    """A dependency letting through users holding any of ``roles`` (or admin)."""
    names = ", ".join(r.value for r in roles) or "admin"

    def check(user: UserDep) -> User:
        if not has_role(user, *roles):
            raise HTTPException(403, f"this needs the role {names}")
        return user

    return check


def bridge_of(state: AppState) -> ZenohBridge:
    if state.bridge is None:
        raise HTTPException(503, "zenoh is disabled in this backend's settings")
    return state.bridge


async def raw_body(request: Request) -> bytes:
    """The request body as bytes (for routes taking a raw file)."""
    return await request.body()


RawBody = Annotated[bytes, Depends(raw_body)]
