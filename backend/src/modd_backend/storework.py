"""A hot route's whole store work in one session (deps.in_store), in the
service's store threads or a store process (storeproc.py): the session
token's user (401), the route's roles (403), the work, the commit."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

from fastapi import HTTPException

from .accounts import user_for_token
from .db import Store
from .roles import Role, parse_roles
from .tables import User

T = TypeVar("T")


def store_work(
    store: Store,
    token: str,
    roles: tuple[Role, ...],
    work: Callable[..., T],
    args: tuple[Any, ...],
) -> T:
    """One session: the token's user (401), ``roles`` (403), ``work``, commit."""
    with store.session() as db:
        user = known(user_for_token(db, token))
        if roles:
            holding(user, roles)
        out = work(db, user, *args)
        db.commit()
        return out


def known(user: User | None) -> User:
    """``user``, or 401 when the token named none."""
    if user is None:
        raise HTTPException(401, "invalid or expired token", headers={"WWW-Authenticate": "Bearer"})
    return user


def holding(user: User, roles: tuple[Role, ...]) -> User:
    """``user``, or 403 when it holds none of ``roles`` (nor admin)."""
    if not has_role(user, *roles):
        names = ", ".join(r.value for r in roles) or "admin"
        raise HTTPException(403, f"this needs the role {names}")
    return user


def roles_of(user: User) -> set[str]:
    return parse_roles(user.roles)


def has_role(user: User, *roles: Role) -> bool:
    held = roles_of(user)
    return Role.admin in held or any(r in held for r in roles)
