"""Tokens and accounts: login, logout, bad tokens, password change, admin-only
user management."""

from __future__ import annotations

from collections.abc import Callable

from fastapi.testclient import TestClient

from .conftest import ADMIN_PASSWORD, Headers, login


def test_login_me_logout(client: TestClient, admin: Headers) -> None:
    me = client.get("/api/auth/me", headers=admin)
    assert me.status_code == 200
    assert me.json()["username"] == "admin"
    assert client.post("/api/auth/logout", headers=admin).status_code == 204
    assert client.get("/api/auth/me", headers=admin).status_code == 401


def test_wrong_password_and_missing_or_bad_token(client: TestClient) -> None:
    r = client.post("/api/auth/login", json={"username": "admin", "password": "nope"})
    assert r.status_code == 401
    r = client.post("/api/auth/login", json={"username": "ghost", "password": "nope"})
    assert r.status_code == 401
    assert client.get("/api/projects").status_code == 401
    bad = {"Authorization": "Bearer not-a-token"}
    assert client.get("/api/projects", headers=bad).status_code == 401
    assert client.get("/api/projects", headers={"Authorization": "Basic eDp5"}).status_code == 401


def test_password_is_stored_hashed(client: TestClient, admin: Headers, settings: object) -> None:
    from modd_backend import Settings
    from sqlalchemy import create_engine, text

    assert isinstance(settings, Settings)
    engine = create_engine(settings.effective_database_url)
    with engine.connect() as conn:
        stored = conn.execute(text("select password_hash from users")).scalar_one()
    engine.dispose()
    assert ADMIN_PASSWORD not in stored
    assert stored.startswith("scrypt$")


def test_change_own_password(client: TestClient, user_factory: Callable[..., Headers]) -> None:
    ann = user_factory("ann", "scientist")
    r = client.put(
        "/api/auth/password",
        headers=ann,
        json={"old_password": "wrong", "new_password": "new-password-1"},
    )
    assert r.status_code == 403
    r = client.put(
        "/api/auth/password",
        headers=ann,
        json={"old_password": "pw-ann-12345", "new_password": "new-password-1"},
    )
    assert r.status_code == 204
    login(client, "ann", "new-password-1")


def test_user_management_is_admin_only(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers]
) -> None:
    for role in ("designer", "integrator", "scientist", "operator"):
        h = user_factory(f"u_{role}", role)
        assert client.get("/api/users", headers=h).status_code == 403
        r = client.post(
            "/api/users",
            headers=h,
            json={"username": "x", "password": "12345678", "roles": ["admin"]},
        )
        assert r.status_code == 403
    users = client.get("/api/users", headers=admin).json()
    bob = next(u for u in users if u["username"] == "u_operator")
    r = client.patch(
        f"/api/users/{bob['id']}", headers=admin, json={"roles": ["operator", "scientist"]}
    )
    assert r.json()["roles"] == ["operator", "scientist"]
    dup = client.post(
        "/api/users",
        headers=admin,
        json={"username": "u_operator", "password": "12345678", "roles": []},
    )
    assert dup.status_code == 409
    assert client.delete(f"/api/users/{bob['id']}", headers=admin).status_code == 204
    assert client.delete(f"/api/users/{bob['id']}", headers=admin).status_code == 404


def test_unknown_role_is_rejected(client: TestClient, admin: Headers) -> None:
    r = client.post(
        "/api/users",
        headers=admin,
        json={"username": "x", "password": "12345678", "roles": ["pilot"]},
    )
    assert r.status_code == 422
