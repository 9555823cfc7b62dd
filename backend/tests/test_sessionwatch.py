"""One session re-check per session, however many sockets are open on it
(docs/security.md, "Revocation"): 1,000 watchers of one session cost one
store query per period, and all hear the verdict at once."""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Iterator
from pathlib import Path

from modd_backend.accounts import create_user, login, logout
from modd_backend.db import Store
from modd_backend.deps import AppState
from modd_backend.sessionwatch import watch_session
from modd_backend.settings import Settings
from sqlalchemy.orm import Session


def test_a_thousand_sockets_share_one_check(tmp_path: Path) -> None:
    settings = Settings(data_dir=tmp_path, ws_recheck_s=0.05)
    store = Store.open(settings.effective_database_url)
    state = AppState(settings, store, None)
    with store.session() as db:
        create_user(db, "ann", "pw-ann-12345", {"scientist"})
        db.commit()
        found = login(db, "ann", "pw-ann-12345", 3600)
        assert found is not None
        token, user = found
        seen = (user.id, user.roles)
    queries = 0
    opened = store.session

    @contextlib.contextmanager
    def counted() -> Iterator[Session]:
        nonlocal queries
        queries += 1
        with opened() as db:
            yield db

    store.session = counted  # type: ignore[method-assign]

    async def run() -> list[tuple[int, str]]:
        waiters = [asyncio.create_task(watch_session(state, token, seen)) for _ in range(1000)]
        await asyncio.sleep(0.5)  # about 10 periods
        assert not any(w.done() for w in waiters)
        assert queries <= 15, f"{queries} store queries for 1,000 sockets in 10 periods"
        store.session = opened  # type: ignore[method-assign]
        with store.session() as db:
            logout(db, token)
        return await asyncio.wait_for(asyncio.gather(*waiters), 5)

    try:
        verdicts = asyncio.run(run())
    finally:
        store.close()
    assert verdicts == [(4401, "the session ended")] * 1000
