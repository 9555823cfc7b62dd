"""User accounts (admin only): list, create, change roles or password, delete."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Depends
from pydantic import BaseModel, Field
from sqlalchemy import select
from sqlalchemy.exc import IntegrityError
from sqlalchemy.orm.exc import ObjectDeletedError, StaleDataError

from ..accounts import admins_left, create_user, revoke_sessions
from ..deps import DbDep, UserDep, require
from ..errors import ApiError
from ..roles import Role, format_roles
from ..schemas import Id
from ..security import hash_password
from ..tables import User
from .auth import UserOut, user_out

router = APIRouter(prefix="/api/users", tags=["users"], dependencies=[Depends(require(Role.admin))])


class UserIn(BaseModel):
    username: Annotated[str, Field(min_length=1, max_length=64, pattern=r"^[A-Za-z0-9_.@-]+$")]
    password: str = Field(min_length=8, max_length=1024)
    roles: list[Role] = Field(max_length=5)


class UserPatch(BaseModel):
    password: str | None = Field(default=None, min_length=8, max_length=1024)
    roles: list[Role] | None = Field(default=None, max_length=5)


def _user(db: DbDep, user_id: int) -> User:
    user = db.get(User, user_id)
    if user is None:
        raise ApiError(404, f"no user {user_id}")
    return user


@router.get("")
def list_users(db: DbDep) -> list[UserOut]:
    return [user_out(u) for u in db.scalars(select(User).order_by(User.id))]


@router.post("", status_code=201, responses={409: {"description": "user name taken"}})
def add_user(body: UserIn, db: DbDep) -> UserOut:
    try:
        user = create_user(db, body.username, body.password, {r.value for r in body.roles})
        db.commit()
    except IntegrityError:
        db.rollback()
        raise ApiError(409, f"the user name {body.username!r} is taken") from None
    return user_out(user)


@router.patch(
    "/{user_id}",
    responses={404: {"description": "no such user"}, 409: {"description": "the last admin"}},
)
def change_user(user_id: Id, body: UserPatch, db: DbDep) -> UserOut:
    """A new password ends every session of the user; the last admin keeps
    the role admin (409). A user deleted meanwhile (a racing DELETE): 404."""
    user = _user(db, user_id)
    try:
        if body.roles is not None:
            user.roles = format_roles({r.value for r in body.roles})
            db.flush()
            if admins_left(db) == 0:
                db.rollback()
                raise ApiError(409, "the last admin cannot lose the role admin")
        if body.password is not None:
            user.password_hash = hash_password(body.password)
            revoke_sessions(db, user.id)
        out = user_out(user)
        db.commit()
    except (StaleDataError, ObjectDeletedError):  # the row went while we changed it
        db.rollback()
        raise ApiError(404, f"no user {user_id}") from None
    return out


@router.delete("/{user_id}", status_code=204, responses={404: {"description": "no such user"}})
def delete_user(user_id: Id, db: DbDep, me: UserDep) -> None:
    user = _user(db, user_id)
    if user.id == me.id:
        raise ApiError(409, "you cannot delete yourself")
    db.delete(user)
    db.flush()
    if admins_left(db) == 0:
        db.rollback()
        raise ApiError(409, "the last admin cannot be deleted")
    db.commit()
