"""Logins on a shared machine (issue 41): a local process's 50 wrong logins
under random names lock the loopback address for new names, never the admin
who logs in there; the admin's own account limit still holds."""

from __future__ import annotations

import secrets
from pathlib import Path

import httpx2 as httpx
from modd_backend import Settings

from .conftest import ADMIN_PASSWORD
from .served import serve


def _login(base: str, user: str, password: str, source: str) -> httpx.Response:
    with httpx.Client(transport=httpx.HTTPTransport(local_address=source), timeout=60) as c:
        return c.post(f"{base}/api/auth/login", json={"username": user, "password": password})


def _settings(tmp_path: Path) -> Settings:
    return Settings(
        data_dir=tmp_path / "data",
        zenoh_enabled=False,
        initial_admin_password=ADMIN_PASSWORD,
        scene_port=None,
    )


def test_50_wrong_logins_from_a_local_process_do_not_stop_the_admins_right_login(
    tmp_path: Path,
) -> None:
    with serve(_settings(tmp_path)) as base:
        assert _login(base, "admin", ADMIN_PASSWORD, "127.0.0.1").status_code == 200
        spray = [
            _login(
                base, secrets.token_hex(6), "guess", f"127.0.{i // 200}.{i % 200 + 2}"
            ).status_code
            for i in range(52)
        ]
        after = _login(base, "admin", ADMIN_PASSWORD, "127.0.0.1")
        stranger = _login(base, "newcomer", "whatever", "127.0.0.1")
    assert spray[:50] == [401] * 50 and spray[50:] == [429] * 2, spray
    assert after.status_code == 200, after.text
    assert stranger.status_code == 429  # the lock holds for names not known here


def test_the_admins_own_limit_holds_past_the_address_lock(tmp_path: Path) -> None:
    with serve(_settings(tmp_path)) as base:
        assert _login(base, "admin", ADMIN_PASSWORD, "127.0.0.1").status_code == 200
        codes = [_login(base, "admin", "wrong", "127.0.0.7").status_code for _ in range(11)]
        right = _login(base, "admin", ADMIN_PASSWORD, "127.0.0.1")
    assert codes == [401] * 10 + [429], codes
    assert right.status_code == 429  # guessing the admin's password still locks the account
