"""Users and sessions: the first admin, login, token lookup, logout."""

from __future__ import annotations

import sys
from datetime import timedelta
from typing import TextIO

from sqlalchemy import delete, func, select
from sqlalchemy.orm import Session as Db

from .roles import Role, format_roles
from .security import (
    burn_password_check,
    hash_password,
    new_password,
    new_token,
    token_hash,
    verify_password,
)
from .tables import Session, User, utcnow

FIRST_ADMIN = "admin"


def create_user(db: Db, username: str, password: str, roles: set[str]) -> User:
    user = User(username=username, password_hash=hash_password(password), roles=format_roles(roles))
    db.add(user)
    db.flush()
    return user


def ensure_first_admin(db: Db, password: str | None, out: TextIO = sys.stdout) -> bool:
    """Create ``admin`` when there is no user at all; print a drawn password
    once (it is stored only hashed). Returns whether one was created."""
    if db.scalar(select(func.count()).select_from(User)):
        return False
    chosen = password if password is not None else new_password()
    create_user(db, FIRST_ADMIN, chosen, {Role.admin.value})
    db.commit()
    if password is None:
        print(
            f"modd-backend: created the first user {FIRST_ADMIN!r} with password "
            f"{chosen} (shown once; change it)",
            file=out,
            flush=True,
        )
    return True


def login(db: Db, username: str, password: str, ttl_s: int) -> tuple[str, User] | None:
    user = db.scalar(select(User).where(User.username == username))
    if user is None:
        burn_password_check(password)  # same time as a wrong password
        return None
    if not verify_password(password, user.password_hash):
        return None
    token = new_token()
    db.add(
        Session(
            token_hash=token_hash(token),
            user_id=user.id,
            expires_at=utcnow() + timedelta(seconds=ttl_s),
        )
    )
    db.commit()
    return token, user


def user_for_token(db: Db, token: str) -> User | None:
    row = db.get(Session, token_hash(token))
    if row is None or row.expires_at < utcnow():
        return None
    return db.get(User, row.user_id)


def logout(db: Db, token: str) -> None:
    db.execute(delete(Session).where(Session.token_hash == token_hash(token)))
    db.commit()


def revoke_sessions(db: Db, user_id: int, keep_token: str | None = None) -> None:
    """End every session of the user (but ``keep_token``'s); not committed."""
    q = delete(Session).where(Session.user_id == user_id)
    if keep_token is not None:
        q = q.where(Session.token_hash != token_hash(keep_token))
    db.execute(q)


def session_state(db: Db, token: str) -> tuple[int, str] | None:
    """(user id, roles) of a live session, or None: what an open WebSocket
    re-checks (a changed result closes it)."""
    user = user_for_token(db, token)
    return None if user is None else (user.id, user.roles)


def admins_left(db: Db) -> int:
    """Admins in the store, their rows locked until commit (PostgreSQL), so
    two concurrent demotions cannot both see another admin."""
    rows = db.scalars(select(User).where(User.roles.contains(Role.admin.value)).with_for_update())
    return sum(1 for u in rows if Role.admin.value in u.roles.split(","))
