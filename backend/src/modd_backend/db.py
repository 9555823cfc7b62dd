"""The store's engine: opened from the settings, migrated to the latest
Alembic revision at start, one SQLAlchemy session per request.

Several backends may share one database and start together: migrations and
the start-up work after them (the first admin) run under a database-wide lock
(a PostgreSQL advisory lock; an exclusive file lock beside a SQLite file), so
exactly one of them migrates and creates the first admin while the others
wait, then find the work done.

>>> store = Store.open("sqlite:////tmp/modd.sqlite3")     # doctest: +SKIP
>>> with store.session() as s: ...                       # doctest: +SKIP
"""

from __future__ import annotations

import fcntl
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path

from alembic import command
from alembic.config import Config
from sqlalchemy import Engine, create_engine, event, text
from sqlalchemy.orm import Session, sessionmaker

MIGRATIONS = Path(__file__).parent / "migrations"
#: Key of the PostgreSQL advisory lock held while a backend starts (any
#: 64-bit number unique to this application: "MoDD" in ASCII).
STARTUP_LOCK_KEY = 0x4D6F4444


def alembic_config() -> Config:
    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    return cfg


def migrate(engine: Engine) -> None:
    """Bring the database to the latest migration (idempotent)."""
    cfg = alembic_config()
    with engine.begin() as conn:
        cfg.attributes["connection"] = conn
        command.upgrade(cfg, "head")


def _sqlite_pragmas(dbapi_conn: object, _record: object) -> None:
    cur = dbapi_conn.cursor()  # type: ignore[attr-defined]
    cur.execute("PRAGMA foreign_keys=ON")
    cur.execute("PRAGMA journal_mode=WAL")
    cur.execute("PRAGMA busy_timeout=5000")
    cur.close()


def sqlite_path(url: str) -> Path | None:
    """The file of a SQLite URL (None for other databases and in-memory SQLite)."""
    if url.startswith("sqlite:///") and url != "sqlite:///:memory:":
        return Path(url.removeprefix("sqlite:///"))
    return None


@contextmanager
def startup_lock(engine: Engine, url: str) -> Iterator[None]:
    """Hold the database-wide start-up lock (blocks until it is free)."""
    path = sqlite_path(url)
    if engine.dialect.name == "postgresql":
        with engine.connect() as conn:
            conn.execute(text("SELECT pg_advisory_lock(:k)"), {"k": STARTUP_LOCK_KEY})
            conn.commit()
            try:
                yield
            finally:
                conn.execute(text("SELECT pg_advisory_unlock(:k)"), {"k": STARTUP_LOCK_KEY})
                conn.commit()
    elif path is not None:
        with open(path.with_name(path.name + ".lock"), "a") as f:
            fcntl.flock(f, fcntl.LOCK_EX)  # released when the file closes
            yield
    else:
        yield


@dataclass
class Store:
    engine: Engine
    factory: sessionmaker[Session]

    @classmethod
    def open(
        cls, url: str, init: Callable[[Store], None] | None = None, *, migrate_first: bool = True
    ) -> Store:
        """Connect and migrate, then run ``init`` (first-start work such as the
        first admin), both under the start-up lock; a SQLite file's folder is
        created. ``migrate_first=False``: connect only (a store process of a
        service that migrated, storeproc.py)."""
        path = sqlite_path(url)
        if url.startswith("sqlite:"):
            if path is not None:
                path.parent.mkdir(parents=True, exist_ok=True)
            engine = create_engine(url, connect_args={"check_same_thread": False})
            event.listen(engine, "connect", _sqlite_pragmas)
        else:
            engine = create_engine(url, pool_pre_ping=True)
        store = cls(engine, sessionmaker(engine, expire_on_commit=False))
        if not migrate_first:
            return store
        with startup_lock(engine, url):
            migrate(engine)
            if init is not None:
                init(store)
        return store

    @contextmanager
    def session(self) -> Iterator[Session]:
        with self.factory() as s:
            yield s

    def close(self) -> None:
        self.engine.dispose()
