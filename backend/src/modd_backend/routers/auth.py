"""Sessions: log in for a bearer token, log out, who am I, change my password."""

from __future__ import annotations

from fastapi import APIRouter
from pydantic import BaseModel, Field

from .. import accounts
from ..deps import DbDep, StateDep, TokenDep, UserDep, roles_of
from ..errors import ApiError
from ..security import hash_password, verify_password
from ..tables import User

router = APIRouter(prefix="/api/auth", tags=["auth"])


class LoginIn(BaseModel):
    username: str = Field(min_length=1, max_length=64)
    password: str = Field(min_length=1, max_length=1024)


class UserOut(BaseModel):
    id: int
    username: str
    roles: list[str]


class LoginOut(BaseModel):
    token: str
    user: UserOut


class PasswordIn(BaseModel):
    old_password: str = Field(max_length=1024)
    new_password: str = Field(min_length=8, max_length=1024)


def user_out(user: User) -> UserOut:
    return UserOut(id=user.id, username=user.username, roles=sorted(roles_of(user)))


@router.post("/login", responses={401: {"description": "wrong user name or password"}})
def login(body: LoginIn, db: DbDep, state: StateDep) -> LoginOut:
    found = accounts.login(db, body.username, body.password, state.settings.token_ttl_s)
    if found is None:
        raise ApiError(401, "wrong user name or password")
    token, user = found
    return LoginOut(token=token, user=user_out(user))


@router.post("/logout", status_code=204)
def logout(db: DbDep, token: TokenDep) -> None:
    accounts.logout(db, token)


@router.get("/me")
def me(user: UserDep) -> UserOut:
    return user_out(user)


@router.put("/password", status_code=204, responses={403: {"description": "wrong password"}})
def change_password(body: PasswordIn, user: UserDep, db: DbDep) -> None:
    if not verify_password(body.old_password, user.password_hash):
        raise ApiError(403, "the old password is wrong")
    user.password_hash = hash_password(body.new_password)
    db.commit()
