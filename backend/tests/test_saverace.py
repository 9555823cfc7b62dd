"""Concurrent saves never store an unauthorised change and never answer a
wrong 403 (SQLite here; PostgreSQL in test_postgres.py)."""

from __future__ import annotations

from collections.abc import Callable

from fastapi.testclient import TestClient

from .conftest import Headers
from .saverace import race_saves


def test_concurrent_saves_never_store_unauthorised_change(
    client: TestClient, admin: Headers, user_factory: Callable[..., Headers], scenario1: str
) -> None:
    designer = user_factory("des", "designer")
    scientist = user_factory("sci", "scientist")
    bad, statuses = race_saves(client, admin, designer, scientist, scenario1, rounds=40)
    assert bad == [], f"unauthorised revisions stored: {bad}"
    # The honest save may lose the race (409) but is never refused as another role's;
    # the attack is refused (403 when its base was the head it changed, else 409).
    assert set(statuses) <= {"attack 403", "attack 409", "honest 200", "honest 409"}, statuses
