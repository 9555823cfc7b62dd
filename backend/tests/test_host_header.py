"""The Host allow-list reads the whole header: a name or a bracketed IPv6
address, then at most a port. Before, ``localhost:8391@evil.com`` and
``[::1]anything`` passed as loopback names (only the text before the last
colon, or inside the brackets, was compared)."""

from __future__ import annotations

from pathlib import Path

import pytest
from modd_backend import Settings


@pytest.fixture
def settings(tmp_path: Path) -> Settings:
    return Settings(data_dir=tmp_path, zenoh_enabled=False, allowed_hosts=("modd.ship.lan",))


@pytest.mark.parametrize(
    "host",
    [
        "127.0.0.1",
        "127.0.0.1:8080",
        "localhost",
        "LOCALHOST:1",
        "[::1]",
        "[::1]:8000",
        "modd.ship.lan",
        "modd.ship.lan:443",
        "app.localhost:5173",
        " localhost ",
    ],
)
def test_this_service(settings: Settings, host: str) -> None:
    assert settings.host_allowed(host)


@pytest.mark.parametrize(
    "host",
    [
        "localhost:8391@evil.com",
        "localhost@evil.com",
        "[::1]evil.com",
        "[::1]:80:80",
        "localhost:",
        "localhost:http",
        "localhost:123456",
        "localhost/evil",
        "user@localhost",
        "evil.com",
        "127.0.0.1.evil.com",
        "modd.ship.lan.evil.com",
        "",
        ":8080",
        "[]:80",
    ],
)
def test_not_this_service(settings: Settings, host: str) -> None:
    assert not settings.host_allowed(host)
