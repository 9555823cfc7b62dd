"""Fixtures: a backend on a real SQLite file in a temporary data directory,
driven through the ASGI test client, and users of every role."""

from __future__ import annotations

import io
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app

ADMIN_PASSWORD = "admin-password-for-tests"


@pytest.fixture(autouse=True, scope="session")
def _loopback_host() -> Iterator[None]:
    """The backend answers only Host names on its allow-list (loopback by
    default): the test client talks as http://127.0.0.1, not "testserver"
    (session-wide, so module-scoped clients get it too)."""
    import starlette.testclient

    init = starlette.testclient.TestClient.__init__

    def loopback_init(self: TestClient, *args: object, **kwargs: object) -> None:
        kwargs.setdefault("base_url", "http://127.0.0.1")
        init(self, *args, **kwargs)  # type: ignore[arg-type]

    starlette.testclient.TestClient.__init__ = loopback_init  # type: ignore[method-assign]
    yield
    starlette.testclient.TestClient.__init__ = init  # type: ignore[method-assign]


Headers = dict[str, str]


@pytest.fixture
def settings(tmp_path: Path) -> Settings:
    return Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
    )


def app_client(tmp_path: Path, **extra: Any) -> TestClient:
    """A workbench over ``tmp_path`` with these further settings (a ``with`` starts it)."""
    settings = Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        **extra,
    )
    return TestClient(create_app(settings, out=io.StringIO()))


@pytest.fixture
def client(settings: Settings) -> Iterator[TestClient]:
    with TestClient(create_app(settings, out=io.StringIO())) as c:
        yield c


def login(client: TestClient, username: str, password: str) -> Headers:
    r = client.post("/api/auth/login", json={"username": username, "password": password})
    assert r.status_code == 200, r.text
    return {"Authorization": f"Bearer {r.json()['token']}"}


@pytest.fixture
def admin(client: TestClient) -> Headers:
    return login(client, "admin", ADMIN_PASSWORD)


@pytest.fixture
def user_factory(client: TestClient, admin: Headers) -> Callable[..., Headers]:
    """``user_factory("ann", "designer", ...)`` creates the user and logs in."""

    def make(name: str, *roles: str) -> Headers:
        password = f"pw-{name}-12345"
        r = client.post(
            "/api/users",
            headers=admin,
            json={"username": name, "password": password, "roles": list(roles)},
        )
        assert r.status_code == 201, r.text
        return login(client, name, password)

    return make


@pytest.fixture
def scenario1(scenarios_dir: Path) -> str:
    return (scenarios_dir / "scenario1.modd").read_text()


@pytest.fixture
def scenario2(scenarios_dir: Path) -> str:
    return (scenarios_dir / "scenario2.modd").read_text()
