"""A PATCH of a user that a DELETE removes while the PATCH is running
answers 404, not 500 (the DELETE lands between the PATCH's read and its
write: made to happen there, deterministically)."""

from __future__ import annotations

from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend.routers import users
from modd_backend.tables import User

from .conftest import Headers


def _delete_meanwhile(client: TestClient, name: str) -> None:
    store = client.app.state.modd.store  # type: ignore[attr-defined]
    with store.session() as db:
        db.delete(db.query(User).filter_by(username=name).one())
        db.commit()


@pytest.mark.parametrize("change", ["password", "roles"])
def test_patch_racing_delete_answers_404(
    client: TestClient, admin: Headers, monkeypatch: pytest.MonkeyPatch, change: str
) -> None:
    r = client.post(
        "/api/users",
        headers=admin,
        json={"username": "gone", "password": "pw-gone-12345", "roles": ["scientist"]},
    )
    assert r.status_code == 201, r.text
    uid = r.json()["id"]
    hooked = "hash_password" if change == "password" else "format_roles"
    real = getattr(users, hooked)

    def racing(*args: Any) -> Any:
        _delete_meanwhile(client, "gone")  # the DELETE wins the race here
        return real(*args)

    monkeypatch.setattr(users, hooked, racing)
    body = {"password": "pw-new-123456"} if change == "password" else {"roles": ["designer"]}
    r = client.patch(f"/api/users/{uid}", headers=admin, json=body)
    assert r.status_code == 404, r.text
    assert client.get("/api/users", headers=admin).status_code == 200
