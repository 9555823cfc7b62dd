"""Sessions: log in (a bearer token for API clients, or an HttpOnly cookie
for the workbench), log out, who am I, change my password.

Login attempts are throttled per account and per client address (429 with
``Retry-After``), counted before the password check so that concurrent guesses
cannot outrun the count (throttle.py); an account that logged in from an
address before is past that address's lock (its own limit still holds); an
unknown user name costs the same time as a wrong password."""

from __future__ import annotations

from typing import Literal

from anyio import to_thread
from fastapi import APIRouter, Request, Response
from pydantic import BaseModel, Field

from .. import accounts
from ..deps import (
    SESSION_COOKIE,
    AppState,
    CredsDep,
    DbDep,
    StateDep,
    TokenDep,
    UserDep,
    roles_of,
)
from ..errors import ApiError, retry_later
from ..security import csrf_for, hash_password, verify_password
from ..tables import User
from ..throttle import address_key

router = APIRouter(prefix="/api/auth", tags=["auth"])


class LoginIn(BaseModel):
    username: str = Field(min_length=1, max_length=64)
    password: str = Field(min_length=1, max_length=1024)
    #: "token": the token in the answer (API clients send it as a bearer);
    #: "cookie": an HttpOnly SameSite=Strict cookie, no token in the answer.
    session: Literal["token", "cookie"] = "token"


class UserOut(BaseModel):
    id: int
    username: str
    roles: list[str]


class MeOut(UserOut):
    """``csrf``: with a cookie session, the value of ``X-CSRF-Token`` that
    every unsafe request must carry."""

    csrf: str | None = None


class LoginOut(BaseModel):
    token: str | None
    csrf: str | None = None
    user: UserOut


class PasswordIn(BaseModel):
    old_password: str = Field(max_length=1024)
    new_password: str = Field(min_length=8, max_length=1024)


def user_out(user: User) -> UserOut:
    return UserOut(id=user.id, username=user.username, roles=sorted(roles_of(user)))


def client_address(request: Request) -> str:
    return request.client.host if request.client is not None else "unknown"


@router.post(
    "/login",
    responses={
        401: {"description": "wrong user name or password"},
        429: {"description": "too many failed logins; Retry-After"},
    },
)
async def login(body: LoginIn, state: StateDep, request: Request, response: Response) -> LoginOut:
    """Throttled on the event loop; the password is checked in the login's
    own threads (``Settings.login_threads``), never queued behind saves."""
    account = body.username.lower()
    address = address_key(client_address(request))
    # an account that logged in from here before is past this address's lock
    known = state.login_known.has(account, address)
    # counted before the password check, atomically (throttle.py)
    wait = 0.0 if known else state.login_addresses.take(address)
    if wait == 0:
        wait = state.login_accounts.take(account)
        if wait > 0 and not known:
            state.login_addresses.give_back(address)
    if wait > 0:
        raise retry_later(429, "too many failed logins; try again later", wait)
    found = await to_thread.run_sync(_check_login, state, body, limiter=state.login_threads)
    if found is None:
        raise ApiError(401, "wrong user name or password")
    state.login_accounts.clear(account)
    if not known:
        state.login_addresses.give_back(address)
    state.login_known.add(account, address)
    token, user = found
    if body.session == "cookie":
        response.set_cookie(
            SESSION_COOKIE,
            token,
            max_age=state.settings.token_ttl_s,
            path="/",
            httponly=True,
            samesite="strict",
            secure=request.url.scheme == "https",
        )
        return LoginOut(token=None, csrf=csrf_for(token), user=user)
    return LoginOut(token=token, user=user)


def _check_login(state: AppState, body: LoginIn) -> tuple[str, UserOut] | None:
    with state.store.session() as db:
        found = accounts.login(db, body.username, body.password, state.settings.token_ttl_s)
        return None if found is None else (found[0], user_out(found[1]))


@router.post("/logout", status_code=204)
def logout(db: DbDep, creds: CredsDep, response: Response) -> None:
    accounts.logout(db, creds.token)
    if creds.via_cookie:
        response.delete_cookie(SESSION_COOKIE, path="/", httponly=True, samesite="strict")


@router.get("/me")
def me(user: UserDep, creds: CredsDep) -> MeOut:
    return MeOut(
        **user_out(user).model_dump(), csrf=csrf_for(creds.token) if creds.via_cookie else None
    )


@router.put("/password", status_code=204, responses={403: {"description": "wrong password"}})
def change_password(body: PasswordIn, user: UserDep, db: DbDep, token: TokenDep) -> None:
    """Also ends every other session of the user (their open sockets close)."""
    if not verify_password(body.old_password, user.password_hash):
        raise ApiError(403, "the old password is wrong")
    user.password_hash = hash_password(body.new_password)
    accounts.revoke_sessions(db, user.id, keep_token=token)
    db.commit()
