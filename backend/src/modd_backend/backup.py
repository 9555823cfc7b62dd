"""``modd-backend backup`` and ``restore``: a consistent copy of the store
while the service runs, and putting one back (docs/operations.md, "Backing up
the store and the archives").

SQLite: the online backup API (a consistent snapshot even while backends
write). A restore checks the copy first — a SQLite database of this
project's schema (its tables and indexes, nothing else: no trigger, no view,
a known migration), intact — and refuses anything else before touching the
store; then it stages the copy beside the store with every session removed
(a restore revokes every session, including those of the backup's time),
and writes the staged copy into the live file in one step under SQLite's
own lock: running requests see the old store or the new one, never a mix.
Files are written 0600 in a 0700 directory. PostgreSQL: ``pg_dump
--format=custom``; a restore loads the archive's rows of this project's
tables itself and runs nothing of the archive (pgrestore.py); the password
travels in ``PGPASSWORD``, never in argv.

    modd-backend backup --data ./data store.backup
    modd-backend restore --data ./data store.backup
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sqlite3
import subprocess
import sys
from pathlib import Path

from sqlalchemy.engine import make_url

from .db import sqlite_path
from .settings import Settings


def _pg_command(tool: str, url: str) -> tuple[list[str], dict[str, str]]:
    """The libpq form of a SQLAlchemy URL, without its password (in the environment)."""
    u = make_url(url)
    env = dict(os.environ)
    if u.password:
        env["PGPASSWORD"] = str(u.password)
    conn = u.set(drivername="postgresql", password=None).render_as_string(hide_password=False)
    exe = shutil.which(tool)
    if exe is None:
        raise SystemExit(f"modd-backend: {tool} not found (apt-get install postgresql-client)")
    return [exe, "--dbname", conn], env


def backup(url: str, out: Path) -> None:
    """Write a consistent copy of the store at ``url`` to ``out`` (replaced atomically)."""
    tmp = out.with_name(f".{out.name}.tmp")
    path = sqlite_path(url)
    try:
        if path is not None:
            if not path.exists():
                raise SystemExit(f"modd-backend: no database at {path}")
            with sqlite3.connect(path) as src, sqlite3.connect(tmp) as dst:
                src.backup(dst)
            # sqlite3's context manager commits but does not close
            src.close()
            dst.close()
        elif url.startswith("postgresql"):
            cmd, env = _pg_command("pg_dump", url)
            subprocess.run([*cmd, "--format=custom", "--file", str(tmp)], env=env, check=True)
        else:
            raise SystemExit(f"modd-backend: cannot back up {make_url(url).drivername}")
        os.chmod(tmp, 0o600)
        os.replace(tmp, out)
    finally:
        tmp.unlink(missing_ok=True)


def _schema_entries() -> set[tuple[str, str]]:
    """(type, name) of what a store of this schema holds (sqlite_master)."""
    from .tables import Base

    out = {("table", "alembic_version"), ("index", "sqlite_autoindex_alembic_version_1")}
    for table in Base.metadata.tables.values():
        out.add(("table", table.name))
        out.update(("index", str(ix.name)) for ix in table.indexes)
        out.update(("index", f"sqlite_autoindex_{table.name}_{k}") for k in range(1, 4))
    return out


def check_sqlite_copy(src: Path) -> None:
    """SystemExit naming what is wrong unless ``src`` is an intact SQLite
    store of this schema at a known migration (read only; nothing runs)."""
    from alembic.script import ScriptDirectory

    from .db import alembic_config

    try:
        with contextlib.closing(
            sqlite3.connect(f"{src.resolve().as_uri()}?mode=ro", uri=True)
        ) as db:
            intact = db.execute("PRAGMA integrity_check").fetchone()
            entries = {
                (str(t), str(n)) for t, n in db.execute("SELECT type, name FROM sqlite_master")
            }
            versions = (
                [r[0] for r in db.execute("SELECT version_num FROM alembic_version")]
                if ("table", "alembic_version") in entries
                else []
            )
    except sqlite3.DatabaseError as exc:
        raise SystemExit(
            f"modd-backend: {src} is not a SQLite database ({exc}); nothing restored"
        ) from None
    if intact != ("ok",):
        raise SystemExit(f"modd-backend: {src} is damaged ({intact}); nothing restored")
    missing = {n for t, n in _schema_entries() if t == "table"} - {n for _, n in entries}
    foreign = sorted(f"{t} {n}" for t, n in entries - _schema_entries())
    if missing or foreign:
        raise SystemExit(
            f"modd-backend: {src} is not a store of this workbench (missing: "
            f"{sorted(missing) or 'none'}; not ours: {foreign or 'none'}); "
            "nothing restored"
        )
    known = {r.revision for r in ScriptDirectory.from_config(alembic_config()).walk_revisions()}
    if len(versions) != 1 or versions[0] not in known:
        raise SystemExit(
            f"modd-backend: {src} is at no migration this backend knows "
            f"({versions}); nothing restored"
        )


def _restore_sqlite(path: Path, src: Path) -> None:
    check_sqlite_copy(src)
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    staged = path.with_name(f".{path.name}.restore")
    staged.unlink(missing_ok=True)
    try:
        with (
            contextlib.closing(sqlite3.connect(src)) as copy,
            contextlib.closing(sqlite3.connect(staged)) as stage,
        ):
            copy.backup(stage)
            stage.execute("DELETE FROM sessions")  # no session outlives a restore
            stage.commit()
        with (
            contextlib.closing(sqlite3.connect(staged)) as stage,
            contextlib.closing(sqlite3.connect(path)) as live,
        ):
            stage.backup(live)  # one step, under the live file's write lock
    finally:
        staged.unlink(missing_ok=True)
    for f in (path, path.with_name(path.name + "-wal"), path.with_name(path.name + "-shm")):
        if f.exists():
            os.chmod(f, 0o600)


def _restore_postgres(url: str, src: Path) -> None:
    """The archive's rows of this project's tables, loaded by the backend
    itself: nothing of the archive runs on the server (pgrestore.py)."""
    from sqlalchemy import create_engine

    from .pgrestore import DumpRefused, load, parse_dump

    exe = shutil.which("pg_restore")
    if exe is None:
        raise SystemExit("modd-backend: pg_restore not found (apt-get install postgresql-client)")
    text = subprocess.run(
        [exe, "--data-only", "--file", "-", str(src)],  # no connection
        capture_output=True,
        check=False,
    )
    if text.returncode != 0:
        raise SystemExit(
            f"modd-backend: {src} is not a pg_dump archive "
            f"({text.stderr.decode(errors='replace').strip()[:200]}); "
            "nothing restored"
        )
    try:
        dump = parse_dump(text.stdout.decode("utf-8", errors="replace"))
    except DumpRefused as exc:
        raise SystemExit(f"modd-backend: {src}: {exc}; nothing restored") from None
    if "users" not in dump.rows:
        raise SystemExit(f"modd-backend: {src} holds no users; nothing restored")
    engine = create_engine(url)
    try:
        with engine.begin() as conn:
            load(conn.connection.driver_connection, dump)
    finally:
        engine.dispose()


def restore(url: str, src: Path) -> None:
    """Put the copy ``src`` back into the store at ``url`` (its contents replaced),
    once it is checked; every session ends."""
    if not src.is_file():
        raise SystemExit(f"modd-backend: no backup at {src}")
    path = sqlite_path(url)
    if path is not None:
        _restore_sqlite(path, src)
    elif url.startswith("postgresql"):
        _restore_postgres(url, src)
    else:
        raise SystemExit(f"modd-backend: cannot restore {make_url(url).drivername}")


def main(argv: list[str]) -> int:
    """``modd-backend backup|restore [--data DIR] [--database-url URL] FILE``."""
    command, rest = argv[0], argv[1:]
    p = argparse.ArgumentParser(
        prog=f"modd-backend {command}", description=f"{command} the workbench's store"
    )
    p.add_argument("--data", type=Path, default=Path("data"), help="data directory")
    p.add_argument(
        "--database-url",
        default=os.environ.get("MODD_DATABASE_URL"),
        help="SQLAlchemy URL (default: $MODD_DATABASE_URL, else SQLite in --data)",
    )
    p.add_argument("file", type=Path, help="the backup file")
    a = p.parse_args(rest)
    os.umask(0o077)  # what a backup or a restore writes: owner only
    url = Settings(data_dir=a.data, database_url=a.database_url).effective_database_url
    try:
        (backup if command == "backup" else restore)(url, a.file)
    except subprocess.CalledProcessError as exc:
        print(f"modd-backend: {command} failed: {exc}", file=sys.stderr)
        return 1
    print(f"modd-backend: {command} {'to' if command == 'backup' else 'from'} {a.file}: done")
    return 0
