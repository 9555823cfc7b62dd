"""Login is never queued behind work (docs/security.md, "Sessions"): with
every worker thread of the service taken, a login still answers at once,
from its own threads, while a route of the shared pool waits."""

from __future__ import annotations

import io
import threading
from pathlib import Path

from anyio import to_thread
from fastapi.testclient import TestClient
from modd_backend import Settings, create_app

from .conftest import ADMIN_PASSWORD


def test_login_answers_with_every_worker_thread_taken(tmp_path: Path) -> None:
    settings = Settings(
        data_dir=tmp_path, zenoh_enabled=False, initial_admin_password=ADMIN_PASSWORD
    )
    holders = [object() for _ in range(4)]
    with TestClient(create_app(settings, out=io.StringIO()), base_url="http://127.0.0.1") as c:
        portal = c.portal
        assert portal is not None
        limiter = portal.call(to_thread.current_default_thread_limiter)
        token = c.post(
            "/api/auth/login", json={"username": "admin", "password": ADMIN_PASSWORD}
        ).json()["token"]

        async def take_all() -> None:
            limiter.total_tokens = 4  # a busy service: every thread at work
            for holder in holders:
                await limiter.acquire_on_behalf_of(holder)

        async def give_back() -> None:
            for holder in holders:
                limiter.release_on_behalf_of(holder)

        portal.call(take_all)
        answers: dict[str, int] = {}

        def ask(name: str, method: str, url: str, **kw: object) -> None:
            answers[name] = c.request(method, url, **kw).status_code  # type: ignore[arg-type]

        login = threading.Thread(
            target=ask,
            args=("login", "POST", "/api/auth/login"),
            kwargs={"json": {"username": "admin", "password": ADMIN_PASSWORD}},
        )
        queued = threading.Thread(  # its user is read in a worker thread
            target=ask,
            args=("projects", "GET", "/api/projects"),
            kwargs={"headers": {"Authorization": f"Bearer {token}"}},
        )
        try:
            queued.start()
            login.start()
            login.join(30)
            assert answers.get("login") == 200, answers
            assert "projects" not in answers  # the shared pool's route still waits
        finally:
            portal.call(give_back)
            login.join(30)
            queued.join(30)
        assert answers["projects"] == 200
