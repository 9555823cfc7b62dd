"""X-Forwarded-For/-Proto are believed only from the reverse proxies named
in ``trusted_proxies``. uvicorn believes them from 127.0.0.1 by default, so
on `make run` any local process could name a new client address per request
and never meet the per-address login throttling: 70 wrong logins under 70
account names, all answered 401 (docs/security.md, "Sessions")."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import httpx2 as httpx
from modd_backend import Settings

from .conftest import ADMIN_PASSWORD
from .served import serve

LIMIT = 5


def _settings(tmp_path: Path, **more: Any) -> Settings:
    return Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        login_limit_address=LIMIT,
        login_limit_account=1000,
        scene_port=None,
        **more,
    )


def _wrong_logins(base: str, n: int) -> list[int]:
    return [
        httpx.post(
            f"{base}/api/auth/login",
            json={"username": f"spray{i}", "password": "wrong"},
            headers={"X-Forwarded-For": f"192.0.2.{i}"},
            timeout=30,
        ).status_code
        for i in range(n)
    ]


def test_forwarded_for_from_an_untrusted_client_is_ignored(tmp_path: Path) -> None:
    with serve(_settings(tmp_path)) as base:
        codes = _wrong_logins(base, LIMIT + 3)
        r = httpx.post(
            f"{base}/api/auth/login",
            timeout=30,
            json={"username": "admin", "password": ADMIN_PASSWORD, "session": "cookie"},
            headers={"X-Forwarded-For": "127.1.1.1", "X-Forwarded-Proto": "https"},
        )
    assert codes[:LIMIT] == [401] * LIMIT and codes[LIMIT:] == [429] * 3, codes
    assert r.status_code == 429  # the address is the socket's, still throttled


def test_a_trusted_proxy_names_the_client(tmp_path: Path) -> None:
    with serve(_settings(tmp_path, trusted_proxies=("127.0.0.1",))) as base:
        codes = _wrong_logins(base, LIMIT + 3)
        r = httpx.post(
            f"{base}/api/auth/login",
            timeout=30,
            json={"username": "admin", "password": ADMIN_PASSWORD, "session": "cookie"},
            headers={"X-Forwarded-For": "127.1.1.1", "X-Forwarded-Proto": "https"},
        )
    assert codes == [401] * (LIMIT + 3), codes  # one address each, as the proxy says
    assert r.status_code == 200 and "secure" in r.headers["set-cookie"].lower()
